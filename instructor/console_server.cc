#include "instructor/console_server.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "common/base/json_text.h"
#include "common/cues/cue_kind.h"
#include "common/scene/scene.h"
#include "common/view/scene_files.h"
#include "common/view/scene_view.h"
#include "instructor/console_message.h"

namespace microdex::instructor {
namespace {

// The station list's readouts: 6 significant digits.
std::string Num(double v) { return JsonNumber(v, 6); }

std::int64_t RealtimeNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double PresenceCode(Presence p) {
  switch (p) {
    case Presence::kAlive:
      return 0;
    case Presence::kLost:
      return 1;
    case Presence::kDeparted:
      return 2;
  }
  return 1;
}

}  // namespace

std::string DefaultWebDir() {
  if (const char* dir = std::getenv("MICRODEX_WEB_DIR"); dir != nullptr && *dir != '\0') {
    return dir;
  }
  return MICRODEX_WEB_DIR;
}

ConsoleServer::ConsoleServer(Instructor& instructor, const std::string& address, int port,
                             const std::string& web_dir, const ConsoleSecurity& security,
                             SessionControl* session)
    : instructor_(instructor),
      session_(session),
      scene_dir_((std::filesystem::temp_directory_path() /
                  ("microdex-console-scenes-" + std::to_string(getpid())))
                     .string()) {
  https_ = !security.tls_cert_file.empty();
  if (!security.users_file.empty()) {
    if (!https_) throw std::runtime_error("console login: needs HTTPS (a certificate and key)");
    auth_ = std::make_unique<ConsoleAuth>(LoadUsers(security.users_file), security.session_idle_s);
  }
  std::map<std::string, view::WebFile> files =
      view::LoadWebFiles(web_dir, {"console.html", "console.js", "frame_worker.js"});
  files["/"] = files["/console.html"];
  view::ViewServerConfig config;
  config.address = address;
  config.port = static_cast<std::uint16_t>(port);
  // One frame per station per period, up to 8 stations, before the page takes them.
  config.max_queued_frames = 24;
  config.frame_credit = 16;
  config.tls_cert_file = security.tls_cert_file;
  config.tls_key_file = security.tls_key_file;
  server_ = std::make_unique<view::ViewServer>(
      config, std::move(files),
      [this](const std::string& target) -> std::optional<view::WebFile> {
        const std::string prefix = "/scene/";
        if (target.starts_with(prefix) && target.ends_with(".json")) {
          return SceneFor(target.substr(prefix.size(), target.size() - prefix.size() - 5));
        }
        return std::nullopt;
      },
      [this] { Poll(); }, [this](const std::string& m) { return HandleMessage(m); });
  if (auth_) {
    server_->SetGate([this](const view::HttpRequestInfo& request, std::string* client) {
      return auth_->Gate(request, client, MonotonicNowNs());
    });
    server_->SetClientTextHandler([this](const std::string& client, const std::string& m) {
      return HandleClientMessage(client, m);
    });
  }
  server_->Start();
}

ConsoleServer::~ConsoleServer() {
  server_->Stop();
  std::error_code ec;
  std::filesystem::remove_all(scene_dir_, ec);
}

// The scene from the station's SceneDescription (the path in its StationInfo names a file on
// the station's machine: it is used only when no description came and that path leads, here,
// to files with the StationInfo's scene_hash). {"error": REASON, "retry": true} while it may still
// come (not received yet, or its hash not yet that of the StationInfo received); a refused or
// unloadable description is logged once per station and reason.
std::optional<view::WebFile> ConsoleServer::SceneFor(const std::string& station_id) {
  std::shared_ptr<const view::SceneFiles> files;
  std::string refused;
  std::string info_path;
  std::uint64_t info_hash = 0;
  bool found = false;
  instructor_.VisitStations([&](const StationView& v) {
    if (v.info.header.station_id != station_id) return;
    found = true;
    files = v.scene_files;
    refused = v.scene_error;
    info_hash = v.info.scene_hash;
    info_path = v.info.scene;
  });
  if (!found) return std::nullopt;
  auto error = [&](const std::string& why, bool retry) {
    if (scene_logged_[station_id] != why && !retry) {
      spdlog::error("console: station '{}': {}", station_id, why);
    }
    scene_logged_[station_id] = why;
    return view::WebFile{"application/json", "{\"error\":" + JsonQuote(why) +
                                                 ",\"retry\":" + (retry ? "true" : "false") + "}"};
  };
  if (!refused.empty()) return error("scene description refused: " + refused, false);
  if (!files && info_hash != 0) {
    // No description (a replay of a recording publishes StationInfo only): the file the
    // StationInfo names, if this machine has it and its files hash to the StationInfo's
    // scene_hash, is certainly the same scene.
    try {
      auto local =
          std::make_shared<view::SceneFiles>(view::CollectSceneFiles(scene::LoadScene(info_path)));
      if (local->hash == info_hash) files = std::move(local);
    } catch (const std::exception&) {
      // Not here: wait for the description.
    }
  }
  if (!files) return error("scene description not received yet", true);
  if (files->hash != info_hash) {
    const std::string why = "scene description hash " + view::HashHex(files->hash) +
                            " differs from the StationInfo's scene_hash " +
                            view::HashHex(info_hash);
    spdlog::warn("console: station '{}': {}", station_id, why);
    return error(why, true);
  }
  auto it = scene_json_.find(files->hash);
  if (it == scene_json_.end()) {
    try {
      const std::string path =
          view::WriteSceneFiles(*files, scene_dir_ + "/" + view::HashHex(files->hash));
      it = scene_json_.emplace(files->hash, view::SceneViewJson(scene::LoadScene(path))).first;
    } catch (const std::exception& e) {
      return error(std::string("scene description does not load: ") + e.what(), false);
    }
  }
  return view::WebFile{"application/json", it->second};
}

std::string ConsoleServer::HandleClientMessage(const std::string& session_token,
                                               const std::string& message) {
  if (auth_) {
    const std::optional<ConsoleSession> s = auth_->Session(session_token, MonotonicNowNs());
    if (!s) throw std::invalid_argument("session expired: log in again");
    if (message.starts_with("cue") && s->role != Role::kInstructor) {
      throw std::invalid_argument("cue: user '" + s->user + "' is an " + RoleName(s->role) +
                                  "; only an instructor sends cues");
    }
    if (IsSessionMessage(message) && s->role != Role::kInstructor) {
      throw std::invalid_argument("session: user '" + s->user + "' is an " + RoleName(s->role) +
                                  "; only an instructor records and replays");
    }
  }
  return HandleMessage(message);
}

std::string ConsoleServer::HandleMessage(const std::string& message) {
  if (IsSessionMessage(message)) {
    if (session_ == nullptr) {
      throw std::invalid_argument(
          "record/replay: this console has no recording folder (microdex-instructor "
          "--record-dir DIR)");
    }
    const SessionCommand command = ParseSessionMessage(message);
    std::string reply;
    try {
      reply = session_->Handle(command);
    } catch (const std::logic_error& e) {
      throw std::invalid_argument(e.what());  // refused
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(e.what());  // the file could not be made or read
    }
    next_status_ns_ = 0;  // show it at once
    return reply;
  }
  const ConsoleCue cue = ParseConsoleMessage(message);
  const std::string& station = cue.station;
  const cues::CueKind kind = cue.kind;
  const double param = cue.param;
  const bool off = cue.off;
  const bool all = station == net::kAllStations;
  if (!all && !instructor_.Station(station)) {
    throw std::invalid_argument("cue: no station '" + station.substr(0, 64) + "'");
  }
  // One command; to every station for "all" (each acknowledges it, shown in its tile).
  const std::uint64_t id = instructor_.SendCue(station, kind, param, 0, off);
  std::vector<std::string> targets;
  if (all) {
    instructor_.VisitStations(
        [&](const StationView& v) { targets.push_back(v.info.header.station_id); });
  } else {
    targets.push_back(station);
  }
  for (const std::string& t : targets) {
    std::vector<SentCue>& sent = sent_[t];
    sent.push_back({id, cues::CueKindName(kind), param, off, RealtimeNowNs()});
    if (sent.size() > kCuesShown) sent.erase(sent.begin());
  }
  next_status_ns_ = 0;  // show it at once
  return "{\"type\":\"cue_sent\",\"station\":" + JsonQuote(station) +
         ",\"cue_id\":" + std::to_string(id) + ",\"kind\":" + JsonQuote(cues::CueKindName(kind)) +
         ",\"param\":" + Num(param) + ",\"off\":" + (off ? "true" : "false") + "}";
}

namespace {

// The cue kinds the panel offers (all but clear), with their parameter's limits.
std::string CueKindsJson() {
  std::string out = "[";
  for (std::uint32_t k = 1; k < cues::kCueKindCount; ++k) {
    const auto kind = static_cast<cues::CueKind>(k);
    const cues::CueParamRange r = cues::CueParamLimits(kind);
    if (k > 1) out += ',';
    out += "{\"kind\":";
    out += JsonQuote(cues::CueKindName(kind));
    out += ",\"bit\":" + std::to_string(k) + ",\"param\":" + JsonQuote(r.name);
    out += ",\"min\":" + Num(r.min) + ",\"max\":" + Num(r.max);
    out += ",\"default\":" + Num(r.default_value) + "}";
  }
  return out + "]";
}

}  // namespace

std::string ConsoleServer::StatusJsonHead() const {
  // The samples this instructor refused (instructor.h RejectedSamples), by topic.
  const RejectedSamples rejected = instructor_.Rejected();
  std::string rej = "{\"total\":" + std::to_string(rejected.total) + ",\"by_topic\":{";
  for (const auto& [topic, n] : rejected.by_topic) {
    if (rej.back() != '{') rej += ',';
    rej += JsonQuote(topic);
    rej += ':';
    rej += std::to_string(n);
  }
  // A reason may quote a hostile sample: printable ASCII only (a WebSocket text frame must be
  // UTF-8).
  std::string latest = rejected.last_reason;
  for (char& ch : latest) {
    if (ch < ' ' || ch > '~') ch = '?';
  }
  rej += "},\"latest\":" + JsonQuote(latest) + "}";
  return "{\"type\":\"stations\",\"issuer_session\":" + JsonQuote(instructor_.session_id()) +
         ",\"cue_kinds\":" + CueKindsJson() + ",\"rejected\":" + rej +
         ",\"session\":" + (session_ ? session_->StatusJson() : std::string("null")) +
         ",\"stations\":[";
}

void ConsoleServer::AppendStationJson(const StationView& v, std::size_t slot, std::int64_t now_ns,
                                      std::string& out) const {
  std::ostringstream j;
  {
    const std::string& id = v.info.header.station_id;
    j << (slot ? "," : "") << "{\"slot\":" << slot << ",\"id\":" << JsonQuote(id)
      << ",\"trainee\":" << JsonQuote(v.info.trainee) << ",\"scene\":" << JsonQuote(v.info.scene)
      << ",\"device\":" << JsonQuote(v.info.device) << ",\"skill\":" << Num(v.info.skill)
      << ",\"presence\":" << JsonQuote(PresenceName(v.presence))
      << ",\"lost_by\":" << JsonQuote(LossSignalName(v.lost_by)) << ",\"comebacks\":" << v.comebacks
      << ",\"heard_ms_ago\":" << Num(static_cast<double>(now_ns - v.last_heard_ns) * 1e-6)
      << ",\"inputs_lost\":" << v.inputs_lost << ",\"modules\":[";
    for (std::size_t m = 0; m < v.info.modules.size(); ++m) {
      j << (m ? "," : "") << JsonQuote(v.info.modules[m]);
    }
    j << "]";
    if (v.telemetry.latest) {
      const net::Telemetry& t = *v.telemetry.latest;
      j << ",\"period_p99_ms\":" << Num(t.period_p99_s * 1e3)
        << ",\"period_max_ms\":" << Num(t.period_max_s * 1e3) << ",\"overruns\":" << t.overruns
        << ",\"realtime\":" << (t.realtime ? "true" : "false")
        << ",\"cues_invalid\":" << t.cues_invalid
        << ",\"device_samples_invalid\":" << t.device_samples_invalid;
    }
    if (v.score.latest) {
      const net::Score& s = *v.score.latest;
      j << ",\"score\":" << Num(s.score) << ",\"progress\":" << Num(s.progress)
        << ",\"outcome\":" << int{s.outcome} << ",\"task\":" << JsonQuote(s.task)
        << ",\"final\":" << (s.is_final ? "true" : "false") << ",\"terms\":[";
      for (std::size_t k = 0; k < s.terms.size(); ++k) {
        j << (k ? "," : "") << "{\"metric\":" << JsonQuote(s.terms[k].metric)
          << ",\"value\":" << Num(s.terms[k].value) << ",\"points\":" << Num(s.terms[k].points)
          << ",\"weight\":" << Num(s.terms[k].weight) << "}";
      }
      j << "]";
    }
    j << ",\"cues\":[";
    if (const auto it = sent_.find(id); it != sent_.end()) {
      for (std::size_t k = 0; k < it->second.size(); ++k) {
        const SentCue& c = it->second[k];
        j << (k ? "," : "") << "{\"cue_id\":" << c.cue_id << ",\"kind\":" << JsonQuote(c.kind)
          << ",\"param\":" << Num(c.param) << ",\"off\":" << (c.off ? "true" : "false")
          << ",\"sent_ms\":" << Num(static_cast<double>(c.sent_realtime_ns) * 1e-6) << ",\"ack\":";
        const net::TaskEvent* ack = nullptr;
        for (const net::TaskEvent& e : v.events) {
          if (e.cue_id == c.cue_id && (e.kind == net::TaskEventKind::kCueApplied ||
                                       e.kind == net::TaskEventKind::kCueRejected)) {
            ack = &e;
          }
        }
        if (ack == nullptr) {
          j << "null";
        } else {
          j << "{\"applied\":" << (ack->kind == net::TaskEventKind::kCueApplied ? "true" : "false")
            << ",\"step\":" << ack->header.step << ",\"text\":" << JsonQuote(ack->text) << "}";
        }
        j << "}";
      }
    }
    j << "]";
    if (!v.scene_error.empty()) j << ",\"scene_error\":" << JsonQuote(v.scene_error);
    j << "}";
  }
  out += j.str();
}

void ConsoleServer::SetPastScores(const std::string& course,
                                  const std::vector<scores::ScoredSession>& sessions) {
  // The latest kPastPerLine of each trainee and scene, in start order.
  std::map<std::pair<std::string, std::string>, std::vector<const scores::ScoredSession*>> lines;
  for (const scores::ScoredSession& s : sessions) lines[{s.trainee, s.scene}].push_back(&s);
  std::string j = "{\"type\":\"past_scores\",\"course\":" + JsonQuote(course) + ",\"lines\":[";
  bool first_line = true;
  for (auto& [key, runs] : lines) {
    std::sort(runs.begin(), runs.end(), [](const auto* a, const auto* b) {
      return std::tie(a->started_ns, a->id) < std::tie(b->started_ns, b->id);
    });
    if (runs.size() > kPastPerLine) runs.erase(runs.begin(), runs.end() - kPastPerLine);
    if (!first_line) j += ',';
    first_line = false;
    j += "{\"trainee\":" + JsonQuote(key.first) + ",\"scene\":" + JsonQuote(key.second) +
         ",\"sessions\":[";
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (i) j += ',';
      j += "{\"id\":" + JsonQuote(runs[i]->id) +
           ",\"started_ms\":" + Num(static_cast<double>(runs[i]->started_ns) * 1e-6) +
           ",\"score\":" + Num(runs[i]->score) + "}";
    }
    j += "]}";
  }
  j += "]}";
  std::lock_guard<std::mutex> lock(past_mutex_);
  if (j != past_json_) {
    past_json_ = std::move(j);
    past_changed_ = true;
  }
}

std::string ConsoleServer::PastScoresJson() const {
  std::lock_guard<std::mutex> lock(past_mutex_);
  return past_json_;
}

// Deltas only: under the registry's lock, a frame for each station whose newest tool state
// FrameForwarder says is due (the others cost a comparison), the station list at
// kStatusRate_hz or when the stations change; nothing of the registry is copied. The frames
// go out after the lock is released. Called every poll period (2 ms).
void ConsoleServer::Poll() {
  const std::int64_t now = MonotonicNowNs();
  bool status_due = now >= next_status_ns_;
  std::vector<std::string> ids;
  if (auth_ && status_due) {
    // An open page keeps its session in use; a session that ended (logout, its lifetime)
    // closes its pages.
    server_->CloseClientsIf([&](const std::string& token) { return !auth_->Session(token, now); });
  }
  std::vector<std::size_t> encoded;  // slots with a new frame
  std::string status;
  const std::int64_t sent_ns = RealtimeNowNs();
  instructor_.VisitStations([&](const StationView& v) {
    const std::size_t i = ids.size();
    ids.push_back(v.info.header.station_id);
    if (status_due) AppendStationJson(v, i, now, status);
    if (!v.tool.latest) return;
    auto forwarder = forwarders_.try_emplace(v.info.header.station_id, kFrameRate_hz).first;
    if (!forwarder->second.Due(v.tool.count, v.tool.received_ns, now)) return;
    if (frames_.size() <= i) frames_.resize(i + 1);
    if (!frames_[i]) frames_[i] = std::make_unique<view::FrameBytes>();
    view::FrameSource src;
    src.slot = static_cast<std::uint32_t>(i);
    src.tool = &*v.tool.latest;
    if (v.needle.latest) src.needle = &*v.needle.latest;
    if (v.thread.latest) src.thread = &*v.thread.latest;
    if (v.tissue.latest) src.tissue = &*v.tissue.latest;
    if (v.score.latest) src.score = &*v.score.latest;
    if (v.telemetry.latest) src.telemetry = &*v.telemetry.latest;
    if (v.overlay.latest) src.overlay = &v.overlay.latest->overlay;
    src.presence = PresenceCode(v.presence);
    src.tool_age_ms = static_cast<double>(now - v.tool.received_ns) * 1e-6;
    src.sent_realtime_ns = sent_ns;
    view::EncodeFrame(src, *frames_[i]);
    encoded.push_back(i);
  });
  // A new list goes out before any frame that uses its slots.
  if (!status_due && ids != ids_) {
    status_due = true;
    std::size_t slot = 0;
    instructor_.VisitStations(
        [&](const StationView& v) { AppendStationJson(v, slot++, now, status); });
  }
  if (status_due) {
    ids_ = ids;
    server_->BroadcastText(StatusJsonHead() + status + "]}");
    next_status_ns_ = now + static_cast<std::int64_t>(1e9 / kStatusRate_hz);
  }
  {
    std::string past;
    {
      std::lock_guard<std::mutex> lock(past_mutex_);
      if (!past_json_.empty() && (past_changed_ || now >= next_past_ns_)) {
        past = past_json_;
        past_changed_ = false;
        next_past_ns_ = now + static_cast<std::int64_t>(kPastPeriod_s * 1e9);
      }
    }
    if (!past.empty()) server_->BroadcastText(past);
  }
  if (encoded.empty()) return;
  // Each period starts at the next station: a page short of credit (view_server.h) loses
  // frames of every station in turn, not always of the last ones.
  ++first_slot_;
  for (std::size_t k = 0; k < encoded.size(); ++k) {
    const std::size_t i = encoded[(first_slot_ + k) % encoded.size()];
    server_->BroadcastBinary(frames_[i]->bytes.data(), frames_[i]->size);
  }
}

}  // namespace microdex::instructor
