#pragma once
// The HTTP + WebSocket server of the view pages (Boost.Beast), on a thread of its own: it
// serves the bundled pages and a scene description, streams binary state frames to every
// connected page, and passes the pages' text messages (device input, cue commands) to a
// handler. Everything of a server — sessions, the poll timer, the handlers — runs on that one
// thread (an asio io_context), so the callbacks need no locks among themselves; the app hands
// data to them through its own lock-free handoffs (the station: a TripleBuffer of frames from
// the publisher thread, an SpscRing of device input to the haptic thread).
//
// Hostile or broken clients: a request header over 8 KiB, a body over 1 KiB, a WebSocket
// message over max_message_bytes, a client that stops reading (more than kMaxQueuedTexts
// replies waiting, or no answer to pings for idle_timeout), or one that floods (more than
// max_messages_per_s messages in a second) is dropped; a text message the handler rejects gets
// {"type":"error","error":REASON} and the connection stays; binary messages from a page are
// rejected the same way. Slow readers lose old state frames, never the newest: a page takes
// frames by credit ("credit N" after it has drawn N; ViewServerConfig::frame_credit), and the
// server drops the frames it has no credit for.
//
// A second binary stream, audio (the station's audio cue blocks, view_audio.h), goes only to the
// pages that asked for it ("audio on"; "audio off" ends it) and takes no credit: a page is
// sent at most max_queued_audio blocks it has not read, newer blocks are dropped beyond (the
// page sees the gap in their sequence numbers), so a slow page loses audio, never holds the
// station.
//
// HTTPS (the instructor's console with --security): with tls_cert_file and tls_key_file set,
// every connection is TLS (OpenSSL through Beast's ssl_stream), pages and WebSocket alike;
// nothing is served in clear. Access control is the app's: a gate (SetGate) sees every
// request first, HTTP and WebSocket upgrade, and either answers it itself (a login form, a
// redirect, 401/403) or lets it through, naming the client (e.g. its session) that the
// WebSocket's text messages are then handed to (SetClientTextHandler).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace microdex::view {

struct ViewServerConfig {
  std::string address = "127.0.0.1";
  std::uint16_t port = 0;  // 0: any free port (port() tells which)
  std::chrono::microseconds poll_period{2000};
  std::size_t max_clients = 16;
  std::size_t max_message_bytes = 4096;  // page → server
  std::size_t max_queued_frames = 3;     // per client; newer frames are dropped beyond
  // Flow control: a page is sent at most this many frames more than it has taken ("credit N"
  // messages after drawing), so a slow page gets the newest frames rather than a backlog
  // held in socket buffers.
  std::size_t frame_credit = 3;
  // Audio blocks waiting to be written to one page (view_audio.h); newer ones are dropped
  // beyond.
  std::size_t max_queued_audio = 8;
  // HTTPS: PEM certificate (chain) and private key; both empty: plain HTTP.
  std::string tls_cert_file;
  std::string tls_key_file;
  // A page that answers no WebSocket ping for this long (it stopped reading, or its network
  // went away) is dropped; pings go out after half of it without traffic.
  std::chrono::milliseconds idle_timeout{10000};
  // A page that sends more messages than this in one second (a flood: a page sends its
  // device input and frame credits at display rate, ~120 a second) is dropped.
  std::size_t max_messages_per_s = 1000;
};

// What a gate sees of a request.
struct HttpRequestInfo {
  std::string method;  // "GET", "POST", ...
  std::string target;  // without the query
  std::string cookie, origin, host;
  std::string body;        // at most 1 KiB
  bool websocket = false;  // an upgrade to the WebSocket
};

// A reply a gate sends instead of the normal handling.
struct HttpReply {
  unsigned status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  // e.g. Set-Cookie, Location
};

struct WebFile {
  std::string content_type;
  std::string body;
};

// Reads `names` from `dir` (the bundled pages); throws std::runtime_error naming a file that
// cannot be read.
std::map<std::string, WebFile> LoadWebFiles(const std::string& dir,
                                            const std::vector<std::string>& names);

// A page's "credit N" message: N (1..ViewServer::kMaxCredit). Throws std::invalid_argument.
long ParseCredit(const std::string& message);

class ViewServer {
 public:
  // Called on the server thread every poll period.
  using PollFn = std::function<void()>;
  // A text message from a page; returns the reply ("" for none). Throws
  // std::invalid_argument(reason) to reject the message (the page gets the reason).
  using TextFn = std::function<std::string(const std::string& message)>;
  // A GET target not among the files (e.g. "/scene.json"); nullopt: 404.
  using DynamicFn = std::function<std::optional<WebFile>(const std::string& target)>;

  // The gate: nullopt lets the request through, with *client set to the name the WebSocket
  // messages of this connection are handed with; a reply answers it instead.
  using GateFn =
      std::function<std::optional<HttpReply>(const HttpRequestInfo&, std::string* client)>;
  // A page's text message with the client its gate named (replaces TextFn when set).
  using ClientTextFn =
      std::function<std::string(const std::string& client, const std::string& message)>;

  // files: by target ("/" included when wanted).
  ViewServer(ViewServerConfig config, std::map<std::string, WebFile> files, DynamicFn dynamic,
             PollFn poll, TextFn on_text);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  // Before Start.
  void SetGate(GateFn gate);
  void SetClientTextHandler(ClientTextFn on_text);

  // Binds and starts the thread; throws std::runtime_error("view server: ADDRESS:PORT: why"),
  // or naming the certificate or key file that cannot be loaded.
  void Start();
  void Stop();
  std::uint16_t port() const { return port_; }

  // Server thread only (the poll and text handlers): send to every open page.
  void BroadcastBinary(const void* data, std::size_t size);
  void BroadcastText(const std::string& text);
  // Server thread only: send to every open page that asked for audio ("audio on").
  void BroadcastAudio(const void* data, std::size_t size);
  std::size_t clients() const;  // server thread only
  // Server thread only: closes the WebSockets whose client (as the gate named it) `close`
  // picks (e.g. their session ended); returns how many.
  std::size_t CloseClientsIf(const std::function<bool(const std::string& client)>& close);

  // Any thread.
  std::uint64_t messages_rejected() const { return rejected_.load(); }
  std::uint64_t frames_dropped() const { return dropped_.load(); }
  std::uint64_t clients_dropped() const { return clients_dropped_.load(); }
  // Pages that asked for audio, as of the last poll period.
  std::size_t audio_clients() const { return audio_clients_.load(std::memory_order_relaxed); }
  std::uint64_t audio_dropped() const { return audio_dropped_.load(); }

  static constexpr std::size_t kMaxQueuedTexts = 64;
  static constexpr std::size_t kMaxCredit = 1024;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint16_t port_ = 0;
  std::atomic<std::uint64_t> rejected_{0}, dropped_{0}, clients_dropped_{0}, audio_dropped_{0};
  std::atomic<std::size_t> audio_clients_{0};
  friend class WsSession;
  template <class Stream>
  friend class WsSessionT;
  template <class Stream>
  friend class HttpSessionT;
};

}  // namespace microdex::view
