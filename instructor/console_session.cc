#include "instructor/console_session.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/base/json_text.h"
#include "common/record/session_reader.h"
#include "common/view/scene_view.h"

namespace microdex::instructor {
namespace {

namespace fs = std::filesystem;

std::string Quote(const std::string& s) { return JsonQuote(s); }
std::string Num(double v) { return JsonNumber(v, 6); }

std::string Join(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) {
    if (!out.empty()) out += ", ";
    out += s;
  }
  return out;
}

std::string StringList(const std::vector<std::string>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) out += ',';
    out += Quote(v[i]);
  }
  return out + "]";
}

std::string DefaultRecordingName() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char name[64];
  std::strftime(name, sizeof name, "session-%Y%m%d-%H%M%S.db", &utc);
  return name;
}

}  // namespace

SessionControl::SessionControl(Instructor& instructor, const std::string& record_dir,
                               net::DdsOptions dds, std::string scene_dir)
    : instructor_(instructor),
      dir_(record_dir),
      dds_(std::move(dds)),
      scene_dir_(std::move(scene_dir)) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (!fs::is_directory(dir_, ec)) {
    throw std::runtime_error("--record-dir " + dir_ + ": not a folder that can be made");
  }
  dds_.participant_name = "microdex-console-replay";
}

SessionControl::~SessionControl() { StopReplays(); }

bool SessionControl::replaying() const {
  return std::any_of(replays_.begin(), replays_.end(),
                     [](const auto& r) { return !r->done.load(); });
}

void SessionControl::EndReplay() {
  for (const auto& r : replays_) {
    if (r->done.load() && r->thread.joinable()) r->thread.join();
  }
}

void SessionControl::StopReplays() {
  for (const auto& r : replays_) r->stop = true;
  for (const auto& r : replays_) {
    if (r->thread.joinable()) r->thread.join();
  }
}

double SessionControl::Position() const {
  double at = 0;
  for (const auto& r : replays_) {
    at = std::max(at, std::clamp(static_cast<double>(r->clock->SessionNowNs() - r->first_ns) * 1e-9,
                                 0.0, r->length_s()));
  }
  return at;
}

double SessionControl::Length() const {
  double length = 0;
  for (const auto& r : replays_) length = std::max(length, r->length_s());
  return length;
}

std::string SessionControl::Handle(const SessionCommand& c) {
  EndReplay();
  using Verb = SessionCommand::Verb;
  switch (c.verb) {
    case Verb::kRecordStart:
      return StartRecording(c.file.empty() ? DefaultRecordingName() : c.file);
    case Verb::kRecordStop: {
      const std::string path = instructor_.RecordingPath();
      if (path.empty()) throw std::invalid_argument("record stop: not recording");
      last_recording_stats_ = instructor_.StopRecording();
      last_recording_ = fs::path(path).filename().string();
      next_list_ns_ = 0;
      const record::RecorderStats& s = *last_recording_stats_;
      spdlog::info("console: recorded {} samples to {} ({} dropped)", s.written, path, s.dropped);
      return "{\"type\":\"recording_stopped\",\"file\":" + Quote(last_recording_) +
             ",\"written\":" + std::to_string(s.written) +
             ",\"dropped\":" + std::to_string(s.dropped) + ",\"error\":" + Quote(s.error) + "}";
    }
    case Verb::kRecordDelete:
      return DeleteRecording(c.file);
    case Verb::kRecordRename:
      return RenameRecording(c.file, c.name);
    case Verb::kReplayPlay:
      return StartReplay(c);
    case Verb::kReplayAdd:
      return AddReplay(c);
    case Verb::kReplayPause:
    case Verb::kReplaySpeed:
    case Verb::kReplaySeek:
    case Verb::kReplayStop:
      return Transport(c);
  }
  throw std::invalid_argument("session: unknown command");
}

std::string SessionControl::Transport(const SessionCommand& c) {
  using Verb = SessionCommand::Verb;
  if (!replaying()) throw std::invalid_argument("replay: nothing is playing");
  if (c.verb == Verb::kReplaySeek && c.from_s > Length()) {
    throw std::invalid_argument("replay seek: " + Num(c.from_s) + " s is past the end (" +
                                Num(Length()) + " s)");
  }
  if (c.verb == Verb::kReplayStop) StopReplays();
  for (const auto& r : replays_) {
    PlayerClock& clock = *r->clock;
    if (c.verb == Verb::kReplayPause) clock.TogglePause();
    if (c.verb == Verb::kReplaySpeed) clock.SetSpeed(c.speed);
    if (c.verb != Verb::kReplaySeek) continue;
    const std::int64_t at =
        r->first_ns + static_cast<std::int64_t>(std::min(c.from_s, r->length_s()) * 1e9);
    if (!r->done.load()) {
      clock.Seek(at);
    } else if (!r->stop.load() && r->error.empty() && c.from_s < r->length_s()) {
      // It had played to its end: it plays again from there.
      if (r->thread.joinable()) r->thread.join();
      auto reader = OpenForReplay("replay seek", r->file, *r);
      clock.Seek(at);
      Launch(*r, std::move(reader), c.from_s);
    }
  }
  const PlayerClock& clock = *replays_.front()->clock;
  return "{\"type\":\"replay\",\"file\":" + Quote(replays_.front()->file) +
         ",\"paused\":" + (clock.paused() ? "true" : "false") + ",\"speed\":" + Num(clock.speed()) +
         ",\"stopped\":" + (c.verb == Verb::kReplayStop ? "true" : "false") + "}";
}

std::string SessionControl::StartRecording(const std::string& name) {
  if (replaying()) {
    throw std::invalid_argument("record start: a replay is playing (" + replays_.front()->file +
                                "); stop it first");
  }
  if (!instructor_.recording_ready()) {
    throw std::invalid_argument("record start: this console was not started ready to record");
  }
  if (const std::string now = instructor_.RecordingPath(); !now.empty()) {
    throw std::invalid_argument("record start: already recording to " +
                                fs::path(now).filename().string());
  }
  const fs::path path = fs::path(dir_) / name;
  std::error_code ec;
  if (fs::exists(path, ec))
    throw std::invalid_argument("record start: " + name + " exists already");
  instructor_.StartRecording(path.string());  // std::runtime_error "PATH: reason"
  next_list_ns_ = 0;
  spdlog::info("console: recording to {}", path.string());
  return "{\"type\":\"recording_started\",\"file\":" + Quote(name) + "}";
}

std::string SessionControl::InUse(const std::string& name) const {
  if (fs::path(instructor_.RecordingPath()).filename().string() == name) {
    return name + " is being recorded; stop it first";
  }
  if (std::any_of(replays_.begin(), replays_.end(),
                  [&](const auto& r) { return r->file == name && !r->done.load(); })) {
    return name + " is playing; stop it first";
  }
  return "";
}

std::string SessionControl::RenameRecording(const std::string& from, const std::string& to) {
  if (const std::string why = InUse(from); !why.empty()) {
    throw std::invalid_argument("record rename: " + why);
  }
  const fs::path src = fs::path(dir_) / from, dst = fs::path(dir_) / to;
  std::error_code ec;
  if (!fs::is_regular_file(src, ec)) {
    throw std::invalid_argument("record rename: no recording " + from + " in " + dir_);
  }
  if (fs::exists(dst, ec)) throw std::invalid_argument("record rename: " + to + " exists already");
  fs::rename(src, dst, ec);
  if (ec) throw std::runtime_error("record rename: " + src.string() + ": " + ec.message());
  // SQLite's companions, left by a recorder that did not close, go with it.
  for (const char* suffix : {"-wal", "-shm", "-journal"}) {
    if (fs::exists(src.string() + suffix, ec))
      fs::rename(src.string() + suffix, dst.string() + suffix, ec);
  }
  cache_.erase(from);
  next_list_ns_ = 0;
  spdlog::info("console: renamed the recording {} to {}", src.string(), to);
  return "{\"type\":\"recording_renamed\",\"file\":" + Quote(from) + ",\"name\":" + Quote(to) + "}";
}

std::string SessionControl::DeleteRecording(const std::string& name) {
  if (const std::string why = InUse(name); !why.empty()) {
    throw std::invalid_argument("record delete: " + why);
  }
  const fs::path path = fs::path(dir_) / name;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw std::invalid_argument("record delete: no recording " + name + " in " + dir_);
  }
  const std::uintmax_t bytes = fs::file_size(path, ec);
  if (!fs::remove(path, ec) || ec) {
    throw std::runtime_error("record delete: " + path.string() + ": " + ec.message());
  }
  // SQLite's companions, left by a recorder that did not close.
  for (const char* suffix : {"-wal", "-shm", "-journal"}) fs::remove(path.string() + suffix, ec);
  cache_.erase(name);
  next_list_ns_ = 0;
  spdlog::info("console: deleted the recording {}", path.string());
  return "{\"type\":\"recording_deleted\",\"file\":" + Quote(name) +
         ",\"bytes\":" + std::to_string(bytes) + "}";
}

std::unique_ptr<record::SessionReader> SessionControl::OpenForReplay(const std::string& verb,
                                                                     const std::string& file,
                                                                     Replay& r) {
  const fs::path path = fs::path(dir_) / file;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw std::invalid_argument(verb + ": no recording " + file + " in " + dir_);
  }
  auto reader = std::make_unique<record::SessionReader>(path.string());  // RecordError
  r.file = file;
  r.stations = reader->Stations();
  std::tie(r.first_ns, r.last_ns) = reader->TimeRange();
  if (r.stations.empty()) throw std::invalid_argument(verb + ": " + file + " is empty");
  // A station alive here now would get the recorded samples mixed into its own (a member
  // played to its end and played again has left).
  std::vector<std::string> live;
  const std::set<std::string> recorded(r.stations.begin(), r.stations.end());
  instructor_.VisitStations([&](const StationView& v) {
    if (v.presence == Presence::kAlive && recorded.count(v.info.header.station_id) > 0) {
      live.push_back(v.info.header.station_id);
    }
  });
  if (!live.empty()) {
    throw std::invalid_argument(verb + ": station " + Join(live) + " of " + file +
                                " is live here; its replay would mix with it");
  }
  return reader;
}

void SessionControl::Launch(Replay& r, std::unique_ptr<record::SessionReader> reader,
                            double from_s) {
  PlayOptions o;
  o.speed = r.clock->speed();
  o.scene_dir = scene_dir_;
  if (from_s > 0) o.from_s = from_s;
  o.wait_for_console_s = 2;  // this console's readers are in this process
  r.stop = false;
  r.done = false;
  r.error.clear();
  Replay* p = &r;
  r.thread = std::thread([this, p, reader = std::move(reader), o]() mutable {
    try {
      const PlayStats stats = Play(*reader, dds_, o, *p->clock, p->stop);
      p->published += stats.published;
      p->scenes_missing = stats.scenes_missing;
    } catch (const std::exception& e) {
      p->error = e.what();
      spdlog::error("console: replay {}: {}", p->file, p->error);
    }
    p->done = true;
  });
}

std::string SessionControl::StartReplay(const SessionCommand& c) {
  if (replaying()) {
    throw std::invalid_argument("replay play: " + replays_.front()->file +
                                " is playing; stop it first, or add to it (replay add FILE)");
  }
  if (!instructor_.RecordingPath().empty()) {
    throw std::invalid_argument("replay play: this console is recording; stop the recording first");
  }
  if (!dds_.security_dir.empty()) {
    throw std::invalid_argument(
        "replay play: not from a secure console (its replay participant has no identity of the "
        "course); use microdex-replay");
  }
  auto replay = std::make_unique<Replay>();
  auto reader = OpenForReplay("replay play", c.file, *replay);
  if (c.from_s >= replay->length_s()) {
    throw std::invalid_argument("replay play: FROM_S " + Num(c.from_s) + " s is past the end (" +
                                Num(replay->length_s()) + " s)");
  }
  replay->clock = std::make_unique<PlayerClock>(
      replay->first_ns + static_cast<std::int64_t>(c.from_s * 1e9), c.speed);
  EndReplay();
  replays_.clear();
  Launch(*replay, std::move(reader), c.from_s);
  replays_.push_back(std::move(replay));
  const Replay& r = *replays_.back();
  spdlog::info("console: replaying {} at {}x from {} s", c.file, c.speed, c.from_s);
  return "{\"type\":\"replay_started\",\"file\":" + Quote(c.file) +
         ",\"stations\":" + StringList(r.stations) + ",\"length_s\":" + Num(r.length_s()) + "}";
}

std::string SessionControl::AddReplay(const SessionCommand& c) {
  if (!replaying()) {
    throw std::invalid_argument("replay add: nothing is playing; start with replay play FILE");
  }
  std::set<std::string> playing;
  for (const auto& r : replays_) {
    if (r->file == c.file) {
      throw std::invalid_argument("replay add: " + c.file + " is in this replay already");
    }
    playing.insert(r->stations.begin(), r->stations.end());
  }
  auto replay = std::make_unique<Replay>();
  auto reader = OpenForReplay("replay add", c.file, *replay);
  std::vector<std::string> shared;
  for (const std::string& s : replay->stations) {
    if (playing.count(s) > 0) shared.push_back(s);
  }
  if (!shared.empty()) {
    throw std::invalid_argument("replay add: station " + Join(shared) + " of " + c.file +
                                " is in this replay already; their samples would mix");
  }
  // From the replay's position, at its speed and pause.
  const double at = Position();
  if (at >= replay->length_s()) {
    throw std::invalid_argument("replay add: " + c.file + " (" + Num(replay->length_s()) +
                                " s) is shorter than the replay's position (" + Num(at) + " s)");
  }
  const PlayerClock& group = *replays_.front()->clock;
  replay->clock = std::make_unique<PlayerClock>(
      replay->first_ns + static_cast<std::int64_t>(at * 1e9), group.speed());
  if (group.paused()) replay->clock->TogglePause();
  Launch(*replay, std::move(reader), at);
  replays_.push_back(std::move(replay));
  const Replay& r = *replays_.back();
  spdlog::info("console: replaying {} alongside, from {} s", c.file, at);
  return "{\"type\":\"replay_added\",\"file\":" + Quote(c.file) +
         ",\"stations\":" + StringList(r.stations) + ",\"length_s\":" + Num(r.length_s()) +
         ",\"from_s\":" + Num(at) + "}";
}

std::vector<RecordingFile> SessionControl::Recordings() {
  const std::string recording = fs::path(instructor_.RecordingPath()).filename().string();
  std::vector<std::pair<fs::file_time_type, std::string>> found;
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!CheckRecordingName(name).empty() || !it->is_regular_file(ec)) continue;
    found.emplace_back(it->last_write_time(ec), name);
  }
  std::sort(found.begin(), found.end(), std::greater<>());
  if (found.size() > kMaxListed) found.resize(kMaxListed);
  std::vector<RecordingFile> out;
  std::map<std::string, Cached> kept;
  for (const auto& [mtime, name] : found) {
    const fs::path path = fs::path(dir_) / name;
    RecordingFile f;
    f.name = name;
    f.bytes = fs::file_size(path, ec);
    if (name == recording) {
      out.push_back(f);  // being written: not opened
      continue;
    }
    const auto c = cache_.find(name);
    if (c != cache_.end() && c->second.mtime == mtime && c->second.bytes == f.bytes) {
      kept[name] = c->second;
      out.push_back(c->second.file);
      continue;
    }
    try {
      record::SessionReader reader(path.string());
      f.stations = reader.Stations();
      const auto [first, last] = reader.TimeRange();
      f.seconds = static_cast<double>(last - first) * 1e-9;
    } catch (const std::exception& e) {
      f.error = e.what();
    }
    kept[name] = Cached{mtime, f.bytes, f};
    out.push_back(f);
  }
  cache_ = std::move(kept);
  return out;
}

std::string SessionControl::StatusJson() {
  EndReplay();
  const std::int64_t now = MonotonicNowNs();
  if (now >= next_list_ns_) {
    listed_ = Recordings();
    next_list_ns_ = now + 1'000'000'000;
  }
  std::string out = "{\"record_dir\":" + Quote(dir_) +
                    ",\"ready\":" + (instructor_.recording_ready() ? "true" : "false") +
                    ",\"can_replay\":" + (dds_.security_dir.empty() ? "true" : "false");
  out += ",\"recording\":";
  const std::string path = instructor_.RecordingPath();
  const std::optional<record::RecorderStats> stats = instructor_.RecorderStats();
  if (!path.empty() && stats) {
    out += "{\"file\":" + Quote(fs::path(path).filename().string()) + ",\"seconds\":" +
           Num(static_cast<double>(now - instructor_.RecordingStartedNs()) * 1e-9) +
           ",\"written\":" + std::to_string(stats->written) +
           ",\"dropped\":" + std::to_string(stats->dropped) + ",\"error\":" + Quote(stats->error) +
           "}";
  } else {
    out += "null";
  }
  out += ",\"last_recording\":";
  if (last_recording_stats_) {
    out += "{\"file\":" + Quote(last_recording_) +
           ",\"written\":" + std::to_string(last_recording_stats_->written) +
           ",\"dropped\":" + std::to_string(last_recording_stats_->dropped) + "}";
  } else {
    out += "null";
  }
  out += ",\"replay\":";
  if (!replays_.empty()) {
    const PlayerClock& clock = *replays_.front()->clock;
    const bool done = !replaying();
    std::vector<std::string> files, stations, missing, errors;
    std::uint64_t published = 0;
    bool stopped = false;
    for (const auto& r : replays_) {
      files.push_back(r->file);
      stations.insert(stations.end(), r->stations.begin(), r->stations.end());
      stopped = stopped || r->stop.load();
      // What its thread writes, read once it has ended (done: acquire).
      if (!r->done.load()) continue;
      published += r->published;
      if (!r->error.empty()) errors.push_back(r->file + ": " + r->error);
      for (const std::string& m : r->scenes_missing) missing.push_back(m);
    }
    out += "{\"file\":" + Quote(files.front()) + ",\"files\":" + StringList(files) +
           ",\"stations\":" + StringList(stations) + ",\"length_s\":" + Num(Length()) +
           ",\"position_s\":" + Num(Position()) + ",\"speed\":" + Num(clock.speed()) +
           ",\"paused\":" + (clock.paused() ? "true" : "false") +
           ",\"seeks\":" + std::to_string(clock.seeks()) + ",\"done\":" + (done ? "true" : "false");
    if (done) {
      out += ",\"published\":" + std::to_string(published) +
             ",\"stopped\":" + (stopped ? "true" : "false") + ",\"error\":" + Quote(Join(errors)) +
             ",\"scenes_missing\":" + StringList(missing);
    }
    out += "}";
  } else {
    out += "null";
  }
  out += ",\"recordings\":[";
  for (std::size_t i = 0; i < listed_.size(); ++i) {
    const RecordingFile& f = listed_[i];
    if (i) out += ',';
    out += "{\"file\":" + Quote(f.name) + ",\"bytes\":" + std::to_string(f.bytes) +
           ",\"seconds\":" + Num(f.seconds) + ",\"stations\":" + StringList(f.stations) +
           ",\"recording\":" + (f.name == fs::path(path).filename().string() ? "true" : "false") +
           ",\"error\":" + Quote(f.error) + "}";
  }
  return out + "]}";
}

}  // namespace microdex::instructor
