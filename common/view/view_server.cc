#include "common/view/view_server.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <cerrno>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "common/base/json_text.h"
#include "common/view/scene_view.h"

namespace microdex::view {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace asio = boost::asio;
using tcp = asio::ip::tcp;

class WsSession;
namespace ssl = asio::ssl;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

struct ViewServer::Impl {
  ViewServerConfig config;
  std::map<std::string, WebFile> files;
  DynamicFn dynamic;
  PollFn poll;
  TextFn on_text;
  ClientTextFn on_client_text;
  GateFn gate;
  std::unique_ptr<ssl::context> tls;  // HTTPS when set
  ViewServer* owner = nullptr;
  asio::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  asio::steady_timer timer{ioc};
  std::vector<std::weak_ptr<WsSession>> sessions;  // server thread only
  std::thread thread;
  bool running = false;

  void Accept();
  void ArmTimer();
  std::size_t OpenSessions();
};

namespace {

std::string ErrorJson(const std::string& reason) {
  return "{\"type\":\"error\",\"error\":" + JsonQuote(reason) + "}";
}

}  // namespace

long ParseCredit(const std::string& message) {
  constexpr std::size_t kPrefix = 7;  // "credit "
  if (message.compare(0, kPrefix, "credit ") != 0) {
    throw std::invalid_argument("credit: expected 'credit N'");
  }
  char* end = nullptr;
  errno = 0;
  const long n = std::strtol(message.c_str() + kPrefix, &end, 10);
  if (end == message.c_str() + kPrefix || *end != '\0' || errno != 0 || n < 1 ||
      n > static_cast<long>(ViewServer::kMaxCredit)) {
    throw std::invalid_argument("credit: expected an integer 1.." +
                                std::to_string(ViewServer::kMaxCredit));
  }
  return n;
}

// One page's WebSocket: reads its text messages, writes queued frames and replies in order.
class WsSession {
 public:
  virtual ~WsSession() = default;
  virtual void Send(const std::shared_ptr<const std::string>& data, bool binary) = 0;
  virtual void SendAudio(const std::shared_ptr<const std::string>& data) = 0;
  virtual bool audio() const = 0;  // open and asked for audio
  virtual const std::string& client() const = 0;
  virtual void Close() = 0;
};

template <class Stream>
class WsSessionT : public WsSession, public std::enable_shared_from_this<WsSessionT<Stream>> {
 public:
  WsSessionT(Stream&& stream, ViewServer::Impl& server, std::string client)
      : ws_(std::move(stream)), server_(server), client_(std::move(client)) {}

  void Run(const http::request<http::string_body>& request) {
    ws_.read_message_max(server_.config.max_message_bytes);
    auto timeout = websocket::stream_base::timeout::suggested(beast::role_type::server);
    timeout.idle_timeout = server_.config.idle_timeout;
    timeout.keep_alive_pings = true;
    ws_.set_option(timeout);
    ws_.async_accept(request,
                     beast::bind_front_handler(&WsSessionT::OnAccept, this->shared_from_this()));
  }

  bool open() const { return open_; }

  void Send(const std::shared_ptr<const std::string>& data, bool binary) override {
    if (!open_) return;
    if (binary) {
      if (credit_ <= 0 || queued_frames_ >= server_.config.max_queued_frames) {
        ++server_.owner->dropped_;
        return;
      }
      --credit_;
      ++queued_frames_;
    } else if (queue_.size() - queued_frames_ - queued_audio_ >= ViewServer::kMaxQueuedTexts) {
      // A page that stops reading its replies: drop it rather than queue without bound.
      ++server_.owner->clients_dropped_;
      spdlog::warn("view: a page stopped reading; closing it");
      Close();
      return;
    }
    queue_.push_back({data, binary, false});
    if (queue_.size() == 1) DoWrite();
  }

  void SendAudio(const std::shared_ptr<const std::string>& data) override {
    if (!open_ || !audio_) return;
    if (queued_audio_ >= server_.config.max_queued_audio) {
      ++server_.owner->audio_dropped_;
      return;
    }
    ++queued_audio_;
    queue_.push_back({data, true, true});
    if (queue_.size() == 1) DoWrite();
  }

  bool audio() const override { return open_ && audio_; }

 private:
  struct Item {
    std::shared_ptr<const std::string> data;
    bool binary = false;
    bool audio = false;  // an audio block (no credit; its own bound)
  };

  void OnAccept(beast::error_code ec) {
    if (ec) return;
    open_ = true;
    DoRead();
  }

  void DoRead() {
    ws_.async_read(buffer_,
                   beast::bind_front_handler(&WsSessionT::OnRead, this->shared_from_this()));
  }

  void OnRead(beast::error_code ec, std::size_t /*bytes*/) {
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        ++server_.owner->rejected_;
        ++server_.owner->clients_dropped_;
        spdlog::warn("view: a page sent a message over {} bytes; dropped it",
                     server_.config.max_message_bytes);
      } else if (ec == beast::error::timeout) {
        ++server_.owner->clients_dropped_;
        spdlog::warn("view: a page answered no ping for {} ms; dropped it",
                     server_.config.idle_timeout.count());
      }
      open_ = false;
      return;
    }
    if (Flooding()) {
      ++server_.owner->rejected_;
      ++server_.owner->clients_dropped_;
      spdlog::warn("view: a page sent over {} messages in a second; dropped it",
                   server_.config.max_messages_per_s);
      Close();
      return;
    }
    if (!ws_.got_text()) {
      ++server_.owner->rejected_;
      Send(std::make_shared<const std::string>(ErrorJson("binary messages are not accepted")),
           false);
    } else {
      const std::string message = beast::buffers_to_string(buffer_.data());
      try {
        if (message.starts_with("credit ")) {
          TakeCredit(message);
          buffer_.consume(buffer_.size());
          DoRead();
          return;
        }
        if (message == "audio on" || message == "audio off") {
          audio_ = message == "audio on";
          buffer_.consume(buffer_.size());
          DoRead();
          return;
        }
        std::string reply = server_.on_client_text ? server_.on_client_text(client_, message)
                                                   : server_.on_text(message);
        if (!reply.empty()) Send(std::make_shared<const std::string>(std::move(reply)), false);
      } catch (const std::invalid_argument& e) {
        ++server_.owner->rejected_;
        Send(std::make_shared<const std::string>(ErrorJson(e.what())), false);
      }
    }
    buffer_.consume(buffer_.size());
    if (open_) DoRead();
  }

  // Counts a message into the current one-second window; true beyond max_messages_per_s.
  bool Flooding() {
    const auto now = std::chrono::steady_clock::now();
    if (now - window_start_ >= std::chrono::seconds(1)) {
      window_start_ = now;
      window_messages_ = 0;
    }
    return ++window_messages_ > server_.config.max_messages_per_s;
  }

  // "credit N": the page has taken N more frames.
  void TakeCredit(const std::string& message) {
    credit_ = std::min<long>(credit_ + ParseCredit(message),
                             static_cast<long>(server_.config.frame_credit));
  }

  void DoWrite() {
    ws_.binary(queue_.front().binary);
    ws_.async_write(asio::buffer(*queue_.front().data),
                    beast::bind_front_handler(&WsSessionT::OnWrite, this->shared_from_this()));
  }

  void OnWrite(beast::error_code ec, std::size_t /*bytes*/) {
    if (ec) {
      open_ = false;
      queue_.clear();
      queued_frames_ = 0;
      queued_audio_ = 0;
      return;
    }
    if (queue_.front().audio) {
      --queued_audio_;
    } else if (queue_.front().binary) {
      --queued_frames_;
    }
    queue_.pop_front();
    if (!queue_.empty() && open_) DoWrite();
  }

  const std::string& client() const override { return client_; }

  void Close() override {
    open_ = false;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
  }

  websocket::stream<Stream> ws_;
  ViewServer::Impl& server_;
  std::string client_;  // as the gate named it
  beast::flat_buffer buffer_;
  std::deque<Item> queue_;
  std::size_t queued_frames_ = 0;
  std::size_t queued_audio_ = 0;
  bool audio_ = false;  // the page asked for audio
  long credit_ = 0;     // frames this page may still be sent before it takes some
  bool open_ = false;
  std::chrono::steady_clock::time_point window_start_{};
  std::size_t window_messages_ = 0;

 public:
  void GrantInitialCredit() { credit_ = static_cast<long>(server_.config.frame_credit); }
};

// One HTTP connection: GET of the pages and the scene, or the upgrade to the WebSocket.
template <class Stream>
class HttpSessionT : public std::enable_shared_from_this<HttpSessionT<Stream>> {
 public:
  HttpSessionT(Stream&& stream, ViewServer::Impl& server)
      : stream_(std::move(stream)), server_(server) {}

  // TLS: the handshake first (30 s at most), then the requests.
  void Start() {
    if constexpr (std::is_same_v<Stream, TlsStream>) {
      beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(30));
      stream_.async_handshake(ssl::stream_base::server,
                              [self = this->shared_from_this()](beast::error_code ec) {
                                if (ec) return;  // not TLS, or a failed handshake: drop it
                                self->DoRead();
                              });
    } else {
      DoRead();
    }
  }

  void DoRead() {
    parser_.emplace();
    parser_->header_limit(8192);
    parser_->body_limit(1024);
    beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     beast::bind_front_handler(&HttpSessionT::OnRead, this->shared_from_this()));
  }

 private:
  void OnRead(beast::error_code ec, std::size_t /*bytes*/) {
    // A TLS client that leaves without close_notify (most do) truncates the stream: a
    // normal end, as end_of_stream is in clear.
    if (ec == http::error::end_of_stream || ec == beast::error::timeout ||
        ec == ssl::error::stream_truncated || ec == asio::error::operation_aborted ||
        ec == asio::error::connection_reset) {
      Shutdown();
      return;
    }
    if (ec) {
      ++server_.owner->rejected_;
      Reply(http::status::bad_request, "text/plain", "bad request: " + ec.message() + "\n", 11,
            false);
      return;
    }
    http::request<http::string_body> req = parser_->release();
    std::string target(req.target());
    if (const auto q = target.find('?'); q != std::string::npos) target.resize(q);
    std::string client;
    if (server_.gate) {
      HttpRequestInfo info;
      info.method = std::string(req.method_string());
      info.target = target;
      info.cookie = std::string(req[http::field::cookie]);
      info.origin = std::string(req[http::field::origin]);
      info.host = std::string(req[http::field::host]);
      info.body = req.body();
      info.websocket = websocket::is_upgrade(req);
      if (std::optional<HttpReply> reply = server_.gate(info, &client)) {
        if (reply->status >= 400) ++server_.owner->rejected_;
        Reply(static_cast<http::status>(reply->status), reply->content_type, reply->body,
              req.version(), req.keep_alive() && !info.websocket, reply->headers);
        return;
      }
    }
    if (websocket::is_upgrade(req)) {
      if (target != "/ws") {
        Reply(http::status::not_found, "text/plain", "no WebSocket at " + target + "\n",
              req.version(), false);
        return;
      }
      if (server_.OpenSessions() >= server_.config.max_clients) {
        Reply(http::status::service_unavailable, "text/plain", "too many pages connected\n",
              req.version(), false);
        return;
      }
      beast::get_lowest_layer(stream_).expires_never();
      // Frames and audio blocks are small messages that should leave at once: no Nagle delay
      // behind an unacknowledged one.
      beast::error_code nodelay_ec;
      beast::get_lowest_layer(stream_).socket().set_option(tcp::no_delay(true), nodelay_ec);
      auto ws = std::make_shared<WsSessionT<Stream>>(std::move(stream_), server_, client);
      ws->GrantInitialCredit();
      server_.sessions.push_back(ws);
      ws->Run(req);
      return;
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      Reply(http::status::method_not_allowed, "text/plain", "only GET\n", req.version(),
            req.keep_alive());
      return;
    }
    if (const auto it = server_.files.find(target); it != server_.files.end()) {
      Reply(http::status::ok, it->second.content_type, it->second.body, req.version(),
            req.keep_alive());
      return;
    }
    std::optional<WebFile> dynamic;
    if (server_.dynamic) dynamic = server_.dynamic(target);
    if (dynamic) {
      Reply(http::status::ok, dynamic->content_type, dynamic->body, req.version(),
            req.keep_alive());
      return;
    }
    Reply(http::status::not_found, "text/plain", "not found: " + target + "\n", req.version(),
          req.keep_alive());
  }

  void Reply(http::status status, const std::string& type, const std::string& body,
             unsigned version, bool keep_alive,
             const std::vector<std::pair<std::string, std::string>>& headers = {}) {
    auto res = std::make_shared<http::response<http::string_body>>(status, version);
    for (const auto& [name, value] : headers) res->insert(name, value);
    res->set(http::field::server, "microdex");
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    // Cross-origin isolation: the pages' frame worker shares its buffer with the page
    // (SharedArrayBuffer); every resource is same-origin.
    res->set("Cross-Origin-Opener-Policy", "same-origin");
    res->set("Cross-Origin-Embedder-Policy", "require-corp");
    if (server_.tls) res->set(http::field::strict_transport_security, "max-age=31536000");
    res->keep_alive(keep_alive);
    res->body() = body;
    res->prepare_payload();
    response_ = res;
    http::async_write(stream_, *res,
                      beast::bind_front_handler(&HttpSessionT::OnWrite, this->shared_from_this()));
  }

  void OnWrite(beast::error_code ec, std::size_t /*bytes*/) {
    if (ec) return;
    const bool keep_alive = response_->keep_alive();
    response_.reset();
    if (!keep_alive) {
      Shutdown();
      return;
    }
    DoRead();
  }

  void Shutdown() {
    beast::error_code ignored;
    beast::get_lowest_layer(stream_).socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  Stream stream_;
  ViewServer::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<http::response<http::string_body>> response_;
};

void ViewServer::Impl::Accept() {
  acceptor.async_accept(ioc, [this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec) {
      if (tls) {
        std::make_shared<HttpSessionT<TlsStream>>(TlsStream(std::move(socket), *tls), *this)
            ->Start();
      } else {
        std::make_shared<HttpSessionT<beast::tcp_stream>>(beast::tcp_stream(std::move(socket)),
                                                          *this)
            ->Start();
      }
    }
    Accept();
  });
}

void ViewServer::Impl::ArmTimer() {
  timer.expires_after(config.poll_period);
  timer.async_wait([this](beast::error_code ec) {
    if (ec) return;
    std::size_t audio = 0;
    for (const std::weak_ptr<WsSession>& w : sessions) {
      if (const std::shared_ptr<WsSession> s = w.lock(); s && s->audio()) ++audio;
    }
    owner->audio_clients_.store(audio, std::memory_order_relaxed);
    if (poll) poll();
    ArmTimer();
  });
}

std::size_t ViewServer::Impl::OpenSessions() {
  std::erase_if(sessions, [](const std::weak_ptr<WsSession>& w) {
    const std::shared_ptr<WsSession> s = w.lock();
    return !s;
  });
  return sessions.size();
}

std::map<std::string, WebFile> LoadWebFiles(const std::string& dir,
                                            const std::vector<std::string>& names) {
  std::map<std::string, WebFile> files;
  for (const std::string& name : names) {
    std::string path = dir;
    path += '/';
    path += name;
    std::ifstream f(path, std::ios::binary);
    if (!f) {
      throw std::runtime_error("view page '" + path +
                               "' not found (build the web_bundle target or set "
                               "MICRODEX_WEB_DIR)");
    }
    std::ostringstream body;
    body << f.rdbuf();
    std::string type = "application/octet-stream";
    if (name.ends_with(".html")) type = "text/html; charset=utf-8";
    if (name.ends_with(".js")) type = "text/javascript; charset=utf-8";
    if (name.ends_with(".css")) type = "text/css; charset=utf-8";
    files["/" + name] = {type, body.str()};
  }
  return files;
}

ViewServer::ViewServer(ViewServerConfig config, std::map<std::string, WebFile> files,
                       DynamicFn dynamic, PollFn poll, TextFn on_text)
    : impl_(std::make_unique<Impl>()) {
  impl_->config = std::move(config);
  impl_->files = std::move(files);
  impl_->dynamic = std::move(dynamic);
  impl_->poll = std::move(poll);
  impl_->on_text = std::move(on_text);
  impl_->owner = this;
}

ViewServer::~ViewServer() { Stop(); }

void ViewServer::SetGate(GateFn gate) { impl_->gate = std::move(gate); }

void ViewServer::SetClientTextHandler(ClientTextFn on_text) {
  impl_->on_client_text = std::move(on_text);
}

void ViewServer::Start() {
  Impl& s = *impl_;
  beast::error_code ec;
  const asio::ip::address address = asio::ip::make_address(s.config.address, ec);
  const std::string where = s.config.address + ":" + std::to_string(s.config.port);
  if (ec) throw std::runtime_error("view server: " + where + ": bad address");
  if (!s.config.tls_cert_file.empty() || !s.config.tls_key_file.empty()) {
    s.tls = std::make_unique<ssl::context>(ssl::context::tls_server);
    s.tls->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 |
                       ssl::context::no_sslv3 | ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
    s.tls->use_certificate_chain_file(s.config.tls_cert_file, ec);
    if (ec) {
      throw std::runtime_error("view server: TLS certificate '" + s.config.tls_cert_file +
                               "': " + ec.message());
    }
    s.tls->use_private_key_file(s.config.tls_key_file, ssl::context::pem, ec);
    if (ec) {
      throw std::runtime_error("view server: TLS key '" + s.config.tls_key_file +
                               "': " + ec.message());
    }
  }
  const tcp::endpoint endpoint(address, s.config.port);
  if (s.acceptor.open(endpoint.protocol(), ec); ec) {
    throw std::runtime_error("view server: " + where + ": " + ec.message());
  }
  s.acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (s.acceptor.bind(endpoint, ec); ec) {
    throw std::runtime_error("view server: " + where + ": " + ec.message());
  }
  if (s.acceptor.listen(asio::socket_base::max_listen_connections, ec); ec) {
    throw std::runtime_error("view server: " + where + ": " + ec.message());
  }
  port_ = s.acceptor.local_endpoint().port();
  s.Accept();
  s.ArmTimer();
  s.running = true;
  s.thread = std::thread([&s] {
    try {
      s.ioc.run();
    } catch (const std::exception& e) {
      spdlog::error("view server stopped: {}", e.what());
    }
  });
}

void ViewServer::Stop() {
  if (!impl_ || !impl_->running) return;
  impl_->ioc.stop();
  impl_->thread.join();
  impl_->running = false;
}

void ViewServer::BroadcastBinary(const void* data, std::size_t size) {
  if (impl_->OpenSessions() == 0) return;
  auto bytes = std::make_shared<const std::string>(static_cast<const char*>(data), size);
  for (const std::weak_ptr<WsSession>& w : impl_->sessions) {
    if (const std::shared_ptr<WsSession> s = w.lock()) s->Send(bytes, true);
  }
}

void ViewServer::BroadcastAudio(const void* data, std::size_t size) {
  if (impl_->OpenSessions() == 0) return;
  std::shared_ptr<const std::string> bytes;
  for (const std::weak_ptr<WsSession>& w : impl_->sessions) {
    if (const std::shared_ptr<WsSession> s = w.lock(); s && s->audio()) {
      if (!bytes) bytes = std::make_shared<const std::string>(static_cast<const char*>(data), size);
      s->SendAudio(bytes);
    }
  }
}

void ViewServer::BroadcastText(const std::string& text) {
  if (impl_->OpenSessions() == 0) return;
  auto bytes = std::make_shared<const std::string>(text);
  for (const std::weak_ptr<WsSession>& w : impl_->sessions) {
    if (const std::shared_ptr<WsSession> s = w.lock()) s->Send(bytes, false);
  }
}

std::size_t ViewServer::clients() const { return impl_->OpenSessions(); }

std::size_t ViewServer::CloseClientsIf(const std::function<bool(const std::string&)>& close) {
  std::size_t closed = 0;
  for (const std::weak_ptr<WsSession>& w : impl_->sessions) {
    if (const std::shared_ptr<WsSession> s = w.lock(); s && close(s->client())) {
      s->Close();
      ++closed;
    }
  }
  return closed;
}

}  // namespace microdex::view
