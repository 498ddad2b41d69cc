#pragma once
// The instructor's live console (`microdex-instructor --http PORT`): serves the console page
// (instructor/page, with the shared front-end of common/view) and, over its WebSocket, one
// binary state frame per station as soon as its mirrored tool state arrives (at most about
// kFrameRate_hz per station: FrameForwarder), and a JSON station list at kStatusRate_hz: the cue
// kinds with their parameter limits, and per station trainee, scene, presence, loop health, live
// score, and the cues this console sent with the station's acknowledgement (applied at step N, or
// rejected and why). The page sends "cue STATION KIND PARAM|off" (every kind of
// common/cues/cue_kind.h), and, with session controls, "record ..." and "replay ..."
// (console_session.h). The scene of a station (/scene/ID.json) comes from the files it
// sent on the SceneDescription topic, checked against the hash in its StationInfo, written
// under a folder of this console's own and loaded there: the console needs none of the
// station's files.
//
// With ConsoleSecurity's files (microdex-instructor --security DIR): HTTPS only, and the
// instructor login of console_auth.h in front of every page, scene and WebSocket; cue
// commands only from a session with the instructor role.
//
// Threads: everything here runs on the view server's thread; it reads the Instructor's
// registry under its lock (VisitStations) and encodes only the stations whose state is new
// (the instructor has no real-time thread).

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/scores/scores_store.h"
#include "common/view/view_frame.h"
#include "common/view/view_server.h"
#include "instructor/console_auth.h"
#include "instructor/console_session.h"
#include "instructor/instructor.h"

namespace microdex::instructor {

// When a station's state goes to the console page: as soon as it arrives (the server polls
// every view::ViewServerConfig::poll_period), at most about rate_hz per station. A state that
// arrives sooner than min_interval after the last one sent is skipped, not held: holding it
// for the slot would show it late by up to the mirror period; the next arrival is sent
// fresh. A skipped state that stays the newest for a whole period (the station went quiet)
// is sent then, so the page ends on the station's last state. A station mirroring at 60 Hz
// is forwarded at 30 Hz, each state within a poll period of its arrival. Pure: tested alone.
class FrameForwarder {
 public:
  explicit FrameForwarder(double rate_hz)
      : min_interval_ns_(static_cast<std::int64_t>(0.8e9 / rate_hz)),
        settle_ns_(static_cast<std::int64_t>(1e9 / rate_hz)) {}
  // count: the station's tool-state count (0: none yet); received_ns: when the newest one
  // arrived; now_ns: the same clock. True: send the newest state now.
  bool Due(std::uint64_t count, std::int64_t received_ns, std::int64_t now_ns) {
    if (count == 0 || count == sent_count_) return false;
    const bool fresh = count != seen_count_;
    seen_count_ = count;
    const bool send = fresh ? sent_count_ == 0 || now_ns - sent_ns_ >= min_interval_ns_
                            : now_ns - received_ns >= settle_ns_;
    if (send) {
      sent_count_ = count;
      sent_ns_ = now_ns;
    }
    return send;
  }

 private:
  std::int64_t min_interval_ns_, settle_ns_;
  std::uint64_t seen_count_ = 0, sent_count_ = 0;
  std::int64_t sent_ns_ = 0;
};

// HTTPS and login (all empty: plain HTTP, no login, as for the demo on one machine).
struct ConsoleSecurity {
  std::string tls_cert_file, tls_key_file;  // PEM
  std::string users_file;                   // console_auth.h; needs TLS
  double session_idle_s = 1800;             // a session unused this long ends
};

class ConsoleServer {
 public:
  // Tiles are small and many: half the stations' default mirror rate is enough for them.
  static constexpr double kFrameRate_hz = 30;
  static constexpr double kStatusRate_hz = 4;
  static constexpr std::size_t kCuesShown = 8;  // per station, the latest

  // Throws std::runtime_error when the pages are missing or the port cannot be bound.
  // `session`: the recording and replay controls (console_session.h), or nullptr for none;
  // it must outlive the server.
  ConsoleServer(Instructor& instructor, const std::string& address, int port,
                const std::string& web_dir, const ConsoleSecurity& security = {},
                SessionControl* session = nullptr);
  ~ConsoleServer();
  ConsoleServer(const ConsoleServer&) = delete;
  ConsoleServer& operator=(const ConsoleServer&) = delete;

  std::uint16_t port() const { return server_->port(); }

  // The reply to a page's text message (throws std::invalid_argument for a bad one).
  std::string HandleMessage(const std::string& message);
  // The station list as the page reads it: the opening, one station, the end.
  std::string StatusJsonHead() const;
  void AppendStationJson(const StationView& v, std::size_t slot, std::int64_t now_ns,
                         std::string& out) const;
  // The same from a logged-in page: its session must still be valid, and a cue, a recording
  // or a replay needs the instructor role (throws std::invalid_argument otherwise).
  std::string HandleClientMessage(const std::string& session_token, const std::string& message);
  bool https() const { return https_; }

  // The final scores of past sessions (the scores database, ScoresWriter::FinalScores) for the
  // page's plot over sessions: at most kPastPerLine of each trainee and scene, the latest.
  // Sent to the pages as a "past_scores" message when it changed and every kPastPeriod_s (so
  // that a page opened later gets it). Any thread.
  static constexpr std::size_t kPastPerLine = 40;
  static constexpr double kPastPeriod_s = 5;
  void SetPastScores(const std::string& course, const std::vector<scores::ScoredSession>& sessions);
  // The "past_scores" message as last set ("" before).
  std::string PastScoresJson() const;

 private:
  struct SentCue {
    std::uint64_t cue_id = 0;
    std::string kind;
    double param = 0;
    bool off = false;
    std::int64_t sent_realtime_ns = 0;
  };
  void Poll();
  std::optional<view::WebFile> SceneFor(const std::string& station_id);

  Instructor& instructor_;
  SessionControl* session_ = nullptr;
  std::map<std::string, std::vector<SentCue>> sent_;  // by station
  std::map<std::string, FrameForwarder> forwarders_;  // by station
  std::map<std::uint64_t, std::string> scene_json_;   // by the scene files' hash
  std::map<std::string, std::string> scene_logged_;   // station → the last scene error logged
  std::string scene_dir_;                             // where received scenes are written
  std::vector<std::string> ids_;                      // slot → station id, as last listed
  std::vector<std::unique_ptr<view::FrameBytes>> frames_;  // per slot, reused
  std::int64_t next_status_ns_ = 0;
  mutable std::mutex past_mutex_;
  std::string past_json_;      // past_mutex_
  bool past_changed_ = false;  // past_mutex_
  std::int64_t next_past_ns_ = 0;
  std::size_t first_slot_ = 0;
  std::unique_ptr<ConsoleAuth> auth_;  // login on when set
  bool https_ = false;
  std::unique_ptr<view::ViewServer> server_;
};

// Where the bundled pages are: $MICRODEX_WEB_DIR, else the build tree's web/ folder.
std::string DefaultWebDir();

}  // namespace microdex::instructor
