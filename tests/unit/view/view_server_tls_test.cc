// The view server over HTTPS with a gate (view_server.h): plain HTTP gets nothing, TLS clients
// get the pages the gate lets through and its own replies otherwise; the WebSocket's messages
// reach the handler with the client the gate named; CloseClientsIf closes the chosen ones.
// The certificate is made here with openssl (self-signed, P-256).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "common/view/view_server.h"

namespace microdex::view {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace asio = boost::asio;
namespace ssl = asio::ssl;
using tcp = asio::ip::tcp;

class ViewServerTls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(::testing::TempDir() + "/view_tls_" + std::to_string(getpid()));
    std::filesystem::create_directories(*dir_);
    const std::string cmd =
        "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 1 "
        "-subj /CN=localhost -keyout " +
        *dir_ + "/key.pem -out " + *dir_ + "/cert.pem > " + *dir_ + "/openssl.log 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << "openssl could not make a certificate";
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete dir_;
  }

  void SetUp() override {
    ViewServerConfig config;
    config.tls_cert_file = *dir_ + "/cert.pem";
    config.tls_key_file = *dir_ + "/key.pem";
    server_ = std::make_unique<ViewServer>(
        config, std::map<std::string, WebFile>{{"/page.html", {"text/html", "<p>page</p>"}}},
        nullptr,
        [this] {  // on the server thread, as an app's poll would
          if (close_alice_.exchange(false)) {
            closed_ = server_->CloseClientsIf([](const std::string& c) { return c == "alice"; });
          }
        },
        [](const std::string&) -> std::string { return "anonymous"; });
    // The gate: cookie k=alice lets through as client "alice"; anything else is 401.
    server_->SetGate([](const HttpRequestInfo& r, std::string* client) -> std::optional<HttpReply> {
      if (r.cookie == "k=alice") {
        *client = "alice";
        return std::nullopt;
      }
      HttpReply reply;
      reply.status = 401;
      reply.body = "who are you\n";
      reply.headers.emplace_back("WWW-Authenticate", "Cookie");
      return reply;
    });
    server_->SetClientTextHandler(
        [](const std::string& client, const std::string& m) { return client + ":" + m; });
    server_->Start();
  }

  // A TLS GET of target with cookie (no certificate check: self-signed).
  http::response<http::string_body> Get(const std::string& target, const std::string& cookie) {
    asio::io_context ioc;
    ssl::context ctx(ssl::context::tls_client);
    beast::ssl_stream<beast::tcp_stream> stream(ioc, ctx);
    beast::get_lowest_layer(stream).connect(
        tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
    stream.handshake(ssl::stream_base::client);
    http::request<http::string_body> req(http::verb::get, target, 11);
    req.set(http::field::host, "127.0.0.1");
    if (!cookie.empty()) req.set(http::field::cookie, cookie);
    http::write(stream, req);
    beast::flat_buffer buffer;
    http::response<http::string_body> res;
    http::read(stream, buffer, res);
    return res;
  }

  static std::string* dir_;
  std::atomic<bool> close_alice_{false};
  std::atomic<std::size_t> closed_{0};
  std::unique_ptr<ViewServer> server_;
};
std::string* ViewServerTls::dir_ = nullptr;

TEST_F(ViewServerTls, PlainHttpGetsNothing) {
  asio::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
  const std::string req = "GET /page.html HTTP/1.1\r\nHost: x\r\nCookie: k=alice\r\n\r\n";
  asio::write(socket, asio::buffer(req));
  std::string got(64, '\0');
  beast::error_code ec;
  const std::size_t n = socket.read_some(asio::buffer(got), ec);
  got.resize(n);
  EXPECT_EQ(got.find("page"), std::string::npos) << got;
  EXPECT_EQ(got.find("HTTP/1.1 200"), std::string::npos) << got;
}

TEST_F(ViewServerTls, TheGateDecidesOverTls) {
  const auto ok = Get("/page.html", "k=alice");
  EXPECT_EQ(ok.result(), http::status::ok);
  EXPECT_EQ(ok.body(), "<p>page</p>");
  EXPECT_EQ(ok[http::field::strict_transport_security], "max-age=31536000");
  const auto no = Get("/page.html", "k=mallory");
  EXPECT_EQ(no.result(), http::status::unauthorized);
  EXPECT_EQ(no.body(), "who are you\n");
  EXPECT_EQ(no["WWW-Authenticate"], "Cookie");
  EXPECT_EQ(server_->messages_rejected(), 1u);
}

TEST_F(ViewServerTls, WebSocketCarriesTheGatesClientAndCanBeClosed) {
  asio::io_context ioc;
  ssl::context ctx(ssl::context::tls_client);
  websocket::stream<beast::ssl_stream<beast::tcp_stream>> ws(ioc, ctx);
  beast::get_lowest_layer(ws).connect(
      tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
  ws.next_layer().handshake(ssl::stream_base::client);
  ws.set_option(websocket::stream_base::decorator(
      [](websocket::request_type& r) { r.set(http::field::cookie, "k=alice"); }));
  ws.handshake("127.0.0.1", "/ws");
  ws.write(asio::buffer(std::string("hello")));
  beast::flat_buffer buffer;
  ws.read(buffer);
  EXPECT_EQ(beast::buffers_to_string(buffer.data()), "alice:hello");

  // Closed by the server thread's poll: the client's next read fails.
  close_alice_ = true;
  buffer.clear();
  beast::error_code ec;
  ws.read(buffer, ec);
  EXPECT_TRUE(ec) << "the WebSocket stayed open";
  // The poll stores its count just after the close the client saw.
  for (int i = 0; i < 500 && closed_.load() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_EQ(closed_.load(), 1u);

  // Without the cookie the upgrade is refused.
  websocket::stream<beast::ssl_stream<beast::tcp_stream>> anon(ioc, ctx);
  beast::get_lowest_layer(anon).connect(
      tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
  anon.next_layer().handshake(ssl::stream_base::client);
  anon.handshake("127.0.0.1", "/ws", ec);
  EXPECT_TRUE(ec);
}

TEST(ViewServerTlsFiles, AMissingCertificateIsNamed) {
  ViewServerConfig config;
  config.tls_cert_file = "/nonexistent/cert.pem";
  config.tls_key_file = "/nonexistent/key.pem";
  ViewServer server(config, {}, nullptr, nullptr, nullptr);
  try {
    server.Start();
    ADD_FAILURE() << "started without its certificate";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cert.pem"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace microdex::view
