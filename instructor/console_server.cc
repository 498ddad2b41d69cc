#include "instructor/console_server.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "common/cues/cue_kind.h"
#include "common/scene/scene.h"
#include "common/view/scene_view.h"

namespace microdex::instructor {
namespace {

std::string Num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

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
                             const std::string& web_dir)
    : instructor_(instructor), frame_(std::make_unique<view::FrameBytes>()) {
  std::map<std::string, view::WebFile> files =
      view::LoadWebFiles(web_dir, {"console.html", "console.js", "frame_worker.js"});
  files["/"] = files["/console.html"];
  view::ViewServerConfig config;
  config.address = address;
  config.port = static_cast<std::uint16_t>(port);
  // One frame per station per period, up to 8 stations, before the page takes them.
  config.max_queued_frames = 24;
  config.frame_credit = 16;
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
  server_->Start();
}

ConsoleServer::~ConsoleServer() { server_->Stop(); }

std::optional<view::WebFile> ConsoleServer::SceneFor(const std::string& station_id) {
  const std::optional<StationView> v = instructor_.Station(station_id);
  if (!v) return std::nullopt;
  const std::string& path = v->info.scene;
  auto it = scene_json_.find(path);
  if (it == scene_json_.end()) {
    std::string json;
    try {
      json = view::SceneViewJson(scene::LoadScene(path));
    } catch (const std::exception& e) {
      // Not on this machine (or not readable): the page draws the tile without a scene.
      json = "{\"error\":" + view::JsonQuote(e.what()) + "}";
    }
    it = scene_json_.emplace(path, std::move(json)).first;
  }
  return view::WebFile{"application/json", it->second};
}

std::string ConsoleServer::HandleMessage(const std::string& message) {
  std::istringstream in(message);
  std::string verb, station, kind_name, param_text;
  in >> verb;
  if (verb != "cue") {
    throw std::invalid_argument("unknown message '" + verb.substr(0, 32) + "' (expected cue)");
  }
  if (!(in >> station >> kind_name >> param_text)) {
    throw std::invalid_argument("cue: expected 'cue STATION KIND PARAM|off'");
  }
  std::string extra;
  if (in >> extra) throw std::invalid_argument("cue: unexpected '" + extra.substr(0, 32) + "'");
  cues::CueKind kind{};
  if (!cues::ParseCueKind(kind_name, &kind)) {
    throw std::invalid_argument("cue: unknown kind '" + kind_name.substr(0, 32) + "' (" +
                                cues::CueKindNames() + ")");
  }
  const bool off = param_text == "off";
  double param = 0;
  if (!off) {
    char* end = nullptr;
    param = std::strtod(param_text.c_str(), &end);
    if (end == param_text.c_str() || *end != '\0' || !std::isfinite(param)) {
      throw std::invalid_argument("cue: PARAM '" + param_text.substr(0, 32) +
                                  "' is neither a number nor off");
    }
  }
  if (const std::string why = cues::CheckCue(kind, param, off); !why.empty()) {
    throw std::invalid_argument("cue: " + why);
  }
  if (!instructor_.Station(station)) {
    throw std::invalid_argument("cue: no station '" + station.substr(0, 64) + "'");
  }
  const std::uint64_t id = instructor_.SendCue(station, kind, param, 0, off);
  std::vector<SentCue>& sent = sent_[station];
  sent.push_back({id, cues::CueKindName(kind), param, off, RealtimeNowNs()});
  if (sent.size() > kCuesShown) sent.erase(sent.begin());
  next_status_ns_ = 0;  // show it at once
  return "{\"type\":\"cue_sent\",\"station\":" + view::JsonQuote(station) +
         ",\"cue_id\":" + std::to_string(id) +
         ",\"kind\":" + view::JsonQuote(cues::CueKindName(kind)) + ",\"param\":" + Num(param) +
         ",\"off\":" + (off ? "true" : "false") + "}";
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
    out += view::JsonQuote(cues::CueKindName(kind));
    out += ",\"bit\":" + std::to_string(k) + ",\"param\":" + view::JsonQuote(r.name);
    out += ",\"min\":" + Num(r.min) + ",\"max\":" + Num(r.max);
    out += ",\"default\":" + Num(r.default_value) + "}";
  }
  return out + "]";
}

}  // namespace

std::string ConsoleServer::StatusJson(const std::vector<StationView>& stations,
                                      std::int64_t now_ns) const {
  std::ostringstream j;
  j << "{\"type\":\"stations\",\"issuer_session\":" << view::JsonQuote(instructor_.session_id())
    << ",\"cue_kinds\":" << CueKindsJson() << ",\"stations\":[";
  for (std::size_t i = 0; i < stations.size(); ++i) {
    const StationView& v = stations[i];
    const std::string& id = v.info.header.station_id;
    j << (i ? "," : "") << "{\"slot\":" << i << ",\"id\":" << view::JsonQuote(id)
      << ",\"trainee\":" << view::JsonQuote(v.info.trainee)
      << ",\"scene\":" << view::JsonQuote(v.info.scene)
      << ",\"device\":" << view::JsonQuote(v.info.device) << ",\"skill\":" << Num(v.info.skill)
      << ",\"presence\":" << view::JsonQuote(PresenceName(v.presence))
      << ",\"lost_by\":" << view::JsonQuote(LossSignalName(v.lost_by))
      << ",\"comebacks\":" << v.comebacks
      << ",\"heard_ms_ago\":" << Num(static_cast<double>(now_ns - v.last_heard_ns) * 1e-6)
      << ",\"inputs_lost\":" << v.inputs_lost << ",\"modules\":[";
    for (std::size_t m = 0; m < v.info.modules.size(); ++m) {
      j << (m ? "," : "") << view::JsonQuote(v.info.modules[m]);
    }
    j << "]";
    if (v.telemetry.latest) {
      const net::Telemetry& t = *v.telemetry.latest;
      j << ",\"period_p99_ms\":" << Num(t.period_p99_s * 1e3)
        << ",\"period_max_ms\":" << Num(t.period_max_s * 1e3) << ",\"overruns\":" << t.overruns
        << ",\"realtime\":" << (t.realtime ? "true" : "false");
    }
    if (v.score.latest) {
      const net::Score& s = *v.score.latest;
      j << ",\"score\":" << Num(s.score) << ",\"progress\":" << Num(s.progress)
        << ",\"outcome\":" << int{s.outcome} << ",\"task\":" << view::JsonQuote(s.task)
        << ",\"final\":" << (s.is_final ? "true" : "false") << ",\"terms\":[";
      for (std::size_t k = 0; k < s.terms.size(); ++k) {
        j << (k ? "," : "") << "{\"metric\":" << view::JsonQuote(s.terms[k].metric)
          << ",\"value\":" << Num(s.terms[k].value) << ",\"points\":" << Num(s.terms[k].points)
          << ",\"weight\":" << Num(s.terms[k].weight) << "}";
      }
      j << "]";
    }
    j << ",\"cues\":[";
    if (const auto it = sent_.find(id); it != sent_.end()) {
      for (std::size_t k = 0; k < it->second.size(); ++k) {
        const SentCue& c = it->second[k];
        j << (k ? "," : "") << "{\"cue_id\":" << c.cue_id << ",\"kind\":" << view::JsonQuote(c.kind)
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
            << ",\"step\":" << ack->header.step << ",\"text\":" << view::JsonQuote(ack->text)
            << "}";
        }
        j << "}";
      }
    }
    j << "]}";
  }
  j << "]}";
  return j.str();
}

void ConsoleServer::Poll() {
  const std::int64_t now = MonotonicNowNs();
  if (now < next_frames_ns_ && now < next_status_ns_) return;
  const std::vector<StationView> stations = instructor_.Stations();
  std::vector<std::string> ids;
  ids.reserve(stations.size());
  for (const StationView& v : stations) ids.push_back(v.info.header.station_id);
  // A new list goes out before any frame that uses its slots.
  if (ids != ids_ || now >= next_status_ns_) {
    ids_ = ids;
    server_->BroadcastText(StatusJson(stations, now));
    next_status_ns_ = now + static_cast<std::int64_t>(1e9 / kStatusRate_hz);
  }
  if (now < next_frames_ns_) return;
  next_frames_ns_ = now + static_cast<std::int64_t>(1e9 / kFrameRate_hz);
  // Each period starts at the next station: a page short of credit (view_server.h) loses
  // frames of every station in turn, not always of the last ones.
  ++first_slot_;
  for (std::size_t k = 0; k < stations.size(); ++k) {
    const std::size_t i = (first_slot_ + k) % stations.size();
    const StationView& v = stations[i];
    if (!v.tool.latest) continue;
    std::uint64_t& sent = frames_sent_[ids[i]];
    if (v.tool.count == sent) continue;
    sent = v.tool.count;
    view::FrameSource src;
    src.slot = static_cast<std::uint32_t>(i);
    src.tool = &*v.tool.latest;
    if (v.needle.latest) src.needle = &*v.needle.latest;
    if (v.thread.latest) src.thread = &*v.thread.latest;
    if (v.tissue.latest) src.tissue = &*v.tissue.latest;
    if (v.score.latest) src.score = &*v.score.latest;
    if (v.telemetry.latest) src.telemetry = &*v.telemetry.latest;
    src.presence = PresenceCode(v.presence);
    src.tool_age_ms = static_cast<double>(now - v.tool.received_ns) * 1e-6;
    src.sent_realtime_ns = RealtimeNowNs();
    view::EncodeFrame(src, *frame_);
    server_->BroadcastBinary(frame_->bytes.data(), frame_->size);
  }
}

}  // namespace microdex::instructor
