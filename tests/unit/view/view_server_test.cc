// The view server against a real client on 127.0.0.1: pages and dynamic targets served, 404 and
// 400 for what is not, the WebSocket's text handler with its error replies, binary messages
// refused, oversized messages dropping the connection, frames broadcast and held back without
// credit.
#include "common/view/view_server.h"

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace microdex::view {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace asio = boost::asio;
using tcp = asio::ip::tcp;

struct Fixture {
  std::atomic<int> polls{0};
  std::atomic<bool> broadcast{false};
  std::atomic<int> audio_burst{0};  // audio messages of 64 KiB to broadcast at the next poll
  std::unique_ptr<ViewServer> server;

  Fixture() {
    std::map<std::string, WebFile> files;
    files["/page.html"] = {"text/html", "<p>page</p>"};
    ViewServerConfig config;
    config.port = 0;
    config.max_message_bytes = 256;
    config.frame_credit = 2;
    server = std::make_unique<ViewServer>(
        config, files,
        [](const std::string& target) -> std::optional<WebFile> {
          if (target == "/scene.json") return WebFile{"application/json", "{}"};
          return std::nullopt;
        },
        [this] {
          ++polls;
          if (broadcast.exchange(false)) {
            const std::string frame(100, 'f');
            for (int i = 0; i < 5; ++i) server->BroadcastBinary(frame.data(), frame.size());
          }
          if (const int n = audio_burst.exchange(0); n > 0) {
            const std::string audio(65536, 'a');
            for (int i = 0; i < n; ++i) server->BroadcastAudio(audio.data(), audio.size());
          }
        },
        [](const std::string& m) -> std::string {
          if (m == "hello") return "{\"type\":\"hi\"}";
          throw std::invalid_argument("not hello");
        });
    server->Start();
  }
};

http::response<http::string_body> Get(std::uint16_t port, const std::string& target,
                                      const std::string& raw = "") {
  asio::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  if (raw.empty()) {
    http::request<http::string_body> req(http::verb::get, target, 11);
    req.set(http::field::host, "127.0.0.1");
    http::write(socket, req);
  } else {
    asio::write(socket, asio::buffer(raw));
  }
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(socket, buffer, res);
  return res;
}

TEST(ViewServer, ServesFilesAndDynamicTargets) {
  Fixture f;
  ASSERT_NE(f.server->port(), 0);
  auto page = Get(f.server->port(), "/page.html");
  EXPECT_EQ(page.result(), http::status::ok);
  EXPECT_EQ(page.body(), "<p>page</p>");
  EXPECT_EQ(page[http::field::content_type], "text/html");
  EXPECT_EQ(page["Cross-Origin-Embedder-Policy"], "require-corp");
  EXPECT_EQ(Get(f.server->port(), "/scene.json?x=1").body(), "{}");
  EXPECT_EQ(Get(f.server->port(), "/nothing").result(), http::status::not_found);
  EXPECT_EQ(Get(f.server->port(), "/../../etc/passwd").result(), http::status::not_found);
}

TEST(ViewServer, MalformedRequestsGet400) {
  Fixture f;
  EXPECT_EQ(Get(f.server->port(), "", "GARBAGE\r\n\r\n").result(), http::status::bad_request);
  const std::string huge_header =
      "GET / HTTP/1.1\r\nHost: x\r\nX: " + std::string(20000, 'a') + "\r\n\r\n";
  EXPECT_EQ(Get(f.server->port(), "", huge_header).result(), http::status::bad_request);
}

TEST(ViewServer, WebSocketTextRepliesAndErrors) {
  Fixture f;
  asio::io_context ioc;
  websocket::stream<tcp::socket> ws(ioc);
  ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), f.server->port()));
  ws.handshake("127.0.0.1", "/ws");
  beast::flat_buffer buffer;
  ws.text(true);
  ws.write(asio::buffer(std::string("hello")));
  ws.read(buffer);
  EXPECT_EQ(beast::buffers_to_string(buffer.data()), "{\"type\":\"hi\"}");
  buffer.consume(buffer.size());
  ws.write(asio::buffer(std::string("bye")));
  ws.read(buffer);
  EXPECT_EQ(beast::buffers_to_string(buffer.data()),
            "{\"type\":\"error\",\"error\":\"not hello\"}");
  buffer.consume(buffer.size());
  ws.write(asio::buffer(std::string("credit x")));
  ws.read(buffer);
  EXPECT_NE(beast::buffers_to_string(buffer.data()).find("credit: expected"), std::string::npos);
  buffer.consume(buffer.size());
  ws.binary(true);
  ws.write(asio::buffer(std::string("\x01\x02")));
  ws.read(buffer);
  EXPECT_NE(beast::buffers_to_string(buffer.data()).find("binary messages are not accepted"),
            std::string::npos);
  EXPECT_EQ(f.server->messages_rejected(), 3u);
}

TEST(ViewServer, FramesNeedCredit) {
  Fixture f;
  asio::io_context ioc;
  websocket::stream<tcp::socket> ws(ioc);
  ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), f.server->port()));
  ws.handshake("127.0.0.1", "/ws");
  // Let the server register the session, then broadcast five frames: two pass (the credit).
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  f.broadcast = true;
  beast::flat_buffer buffer;
  for (int i = 0; i < 2; ++i) {
    ws.read(buffer);
    EXPECT_TRUE(ws.got_binary());
    EXPECT_EQ(buffer.size(), 100u);
    buffer.consume(buffer.size());
  }
  for (int i = 0; i < 100 && f.server->frames_dropped() < 3; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(f.server->frames_dropped(), 3u);
  // One credit: the next broadcast's first frame comes.
  ws.text(true);
  ws.write(asio::buffer(std::string("credit 1")));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  f.broadcast = true;
  ws.read(buffer);
  EXPECT_TRUE(ws.got_binary());
  for (int i = 0; i < 100 && f.server->frames_dropped() < 7; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(f.server->frames_dropped(), 7u);
}

// Audio goes only to the pages that asked ("audio on"), without frame credit; a page that
// stops reading loses audio beyond max_queued_audio (8) instead of queueing it.
TEST(ViewServer, AudioOnlyToPagesThatAskAndBounded) {
  Fixture f;
  asio::io_context ioc;
  websocket::stream<tcp::socket> asks(ioc), quiet(ioc);
  for (auto* ws : {&asks, &quiet}) {
    ws->next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), f.server->port()));
    ws->handshake("127.0.0.1", "/ws");
  }
  asks.text(true);
  asks.write(asio::buffer(std::string("audio on")));
  for (int i = 0; i < 100 && f.server->audio_clients() != 1; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(f.server->audio_clients(), 1u);
  f.audio_burst = 3;
  beast::flat_buffer buffer;
  for (int i = 0; i < 3; ++i) {
    asks.read(buffer);
    EXPECT_TRUE(asks.got_binary());
    EXPECT_EQ(buffer.size(), 65536u);
    buffer.consume(buffer.size());
  }
  // The other page gets none: its next message is the reply to its own request.
  quiet.text(true);
  quiet.write(asio::buffer(std::string("hello")));
  quiet.read(buffer);
  EXPECT_TRUE(quiet.got_text());
  buffer.consume(buffer.size());
  EXPECT_EQ(f.server->audio_dropped(), 0u);
  // The asking page stops reading: 64 MiB offered, at most 8 blocks queue beyond the socket's
  // buffers, the rest is dropped.
  for (int burst = 0; burst < 16; ++burst) {
    f.audio_burst = 64;
    for (int i = 0; i < 100 && f.audio_burst != 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  for (int i = 0; i < 100 && f.server->audio_dropped() < 700; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_GE(f.server->audio_dropped(), 700u);
  EXPECT_EQ(f.server->frames_dropped(), 0u);
  EXPECT_EQ(f.server->clients_dropped(), 0u);
  // "audio off": no longer counted.
  asks.write(asio::buffer(std::string("audio off")));
  for (int i = 0; i < 100 && f.server->audio_clients() != 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(f.server->audio_clients(), 0u);
}

TEST(ViewServer, OversizedMessageDropsTheConnection) {
  Fixture f;
  asio::io_context ioc;
  websocket::stream<tcp::socket> ws(ioc);
  ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), f.server->port()));
  ws.handshake("127.0.0.1", "/ws");
  ws.write(asio::buffer(std::string(1000, 'x')));
  beast::flat_buffer buffer;
  beast::error_code ec;
  ws.read(buffer, ec);
  EXPECT_TRUE(ec);  // closed by the server
  for (int i = 0; i < 100 && f.server->clients_dropped() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(f.server->clients_dropped(), 1u);
  // The server still serves.
  EXPECT_EQ(Get(f.server->port(), "/page.html").result(), http::status::ok);
}

TEST(ViewServer, BindFailureNamesTheAddress) {
  Fixture f;
  ViewServerConfig config;
  config.port = f.server->port();
  ViewServer second(config, {}, nullptr, nullptr, nullptr);
  try {
    second.Start();
    FAIL() << "bound a port in use";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("127.0.0.1:" + std::to_string(config.port)),
              std::string::npos);
  }
}

}  // namespace
}  // namespace microdex::view
