// Hostile pages against the view server (label fault): a client that connects and never
// reads, and clients that flood the WebSocket (with replies they never read, or with
// messages that need none), are dropped, while a well-behaved viewer on the same server keeps
// getting its frames (its frame rate while the hostile client is connected, against its own
// rate just before, in the same run).
#include <gtest/gtest.h>

#include <atomic>
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstdio>
#include <thread>

#include "common/view/view_server.h"

namespace microdex::view {
namespace {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace asio = boost::asio;
using tcp = asio::ip::tcp;
using namespace std::chrono_literals;

// A server broadcasting a 1 KiB frame every 2 ms poll; "hello" gets a reply.
struct Server {
  std::unique_ptr<ViewServer> server;
  explicit Server(ViewServerConfig config) {
    server = std::make_unique<ViewServer>(
        config, std::map<std::string, WebFile>{}, nullptr,
        [this] {
          const std::string frame(1024, 'f');
          server->BroadcastBinary(frame.data(), frame.size());
        },
        [](const std::string& m) -> std::string {
          if (m == "hello") return "{\"type\":\"hi\"}";
          throw std::invalid_argument("not hello");
        });
    server->Start();
  }
};

ViewServerConfig FaultConfig() {
  ViewServerConfig config;
  config.idle_timeout = 1000ms;
  config.max_messages_per_s = 1000;
  return config;
}

void Connect(websocket::stream<tcp::socket>& ws, std::uint16_t port) {
  ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  ws.handshake("127.0.0.1", "/ws");
}

// A page that draws every frame it gets and takes the next (credit 1 after each).
class Viewer {
 public:
  explicit Viewer(std::uint16_t port) : ws_(ioc_) {
    Connect(ws_, port);
    thread_ = std::thread([this] {
      beast::flat_buffer buffer;
      beast::error_code ec;
      while (!stop_) {
        ws_.read(buffer, ec);
        if (ec) break;
        if (ws_.got_binary()) ++frames_;
        buffer.consume(buffer.size());
        ws_.text(true);
        ws_.write(asio::buffer(std::string("credit 1")), ec);
        if (ec) break;
      }
      closed_ = true;
    });
  }
  ~Viewer() {
    stop_ = true;
    beast::error_code ignored;
    ws_.next_layer().shutdown(tcp::socket::shutdown_both, ignored);
    thread_.join();
  }
  // Frames per second over `window`.
  double Rate(std::chrono::milliseconds window) const {
    const auto n0 = frames_.load();
    std::this_thread::sleep_for(window);
    return static_cast<double>(frames_.load() - n0) / std::chrono::duration<double>(window).count();
  }
  bool closed() const { return closed_; }

 private:
  asio::io_context ioc_;
  websocket::stream<tcp::socket> ws_;
  std::thread thread_;
  std::atomic<std::uint64_t> frames_{0};
  std::atomic<bool> stop_{false}, closed_{false};
};

bool WaitDropped(const ViewServer& s, std::uint64_t n, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (s.clients_dropped() >= n) return true;
    std::this_thread::sleep_for(10ms);
  }
  return s.clients_dropped() >= n;
}

TEST(ViewServerFault, ClientThatNeverReadsIsDroppedOthersKeepTheirFrames) {
  Server s(FaultConfig());
  Viewer viewer(s.server->port());
  const double before = viewer.Rate(1000ms);

  asio::io_context ioc;
  websocket::stream<tcp::socket> idle(ioc);
  Connect(idle, s.server->port());  // and then never reads nor writes
  const auto t0 = std::chrono::steady_clock::now();
  const double during = viewer.Rate(800ms);
  ASSERT_TRUE(WaitDropped(*s.server, 1, 5s)) << "a client that never reads was kept";
  const double dropped_after_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "never-reading client dropped after %.2f s (idle timeout 1 s); viewer %.0f "
      "frames/s before, %.0f while it was connected\n",
      dropped_after_s, before, during);
  EXPECT_GT(before, 50.0);
  EXPECT_GE(during, 0.5 * before);
  EXPECT_FALSE(viewer.closed());
  EXPECT_EQ(s.server->clients_dropped(), 1u);  // the viewer was not
}

// Sends `message` as fast as it can, never reading; returns the messages it got out.
std::uint64_t Flood(std::uint16_t port, const std::string& message, std::atomic<bool>& stop) {
  asio::io_context ioc;
  websocket::stream<tcp::socket> ws(ioc);
  Connect(ws, port);
  ws.text(true);
  std::uint64_t sent = 0;
  beast::error_code ec;
  while (!stop) {
    ws.write(asio::buffer(message), ec);
    if (ec) break;
    ++sent;
  }
  return sent;
}

void CheckFloodDropped(const std::string& message) {
  Server s(FaultConfig());
  Viewer viewer(s.server->port());
  const double before = viewer.Rate(1000ms);
  std::atomic<bool> stop{false};
  std::uint64_t sent = 0;
  std::thread flooder([&] { sent = Flood(s.server->port(), message, stop); });
  const double during = viewer.Rate(500ms);
  const bool dropped = WaitDropped(*s.server, 1, 5s);
  stop = true;
  flooder.join();
  std::printf(
      "flood of '%s': %llu sent before the server dropped it; viewer %.0f frames/s "
      "before, %.0f during\n",
      message.c_str(), static_cast<unsigned long long>(sent), before, during);
  EXPECT_TRUE(dropped) << "a flooding client was kept";
  EXPECT_GT(before, 50.0);
  EXPECT_GE(during, 0.5 * before);
  EXPECT_FALSE(viewer.closed());
  EXPECT_EQ(s.server->clients_dropped(), 1u);
}

TEST(ViewServerFault, FloodOfMessagesWithRepliesNeverReadIsDropped) { CheckFloodDropped("hello"); }

TEST(ViewServerFault, FloodOfMessagesWithoutRepliesIsDropped) { CheckFloodDropped("credit 1"); }

}  // namespace
}  // namespace microdex::view
