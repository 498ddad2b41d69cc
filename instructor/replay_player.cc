#include "instructor/replay_player.h"

#include <time.h>

#include <algorithm>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

#include "common/record/recorded_topics.h"
#include "common/scene/scene.h"
#include "common/view/scene_description_msg.h"
#include "common/view/scene_files.h"
#include "cue_commandPubSubTypes.h"
#include "cue_overlayPubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "instructor/recorded_sample.h"
#include "needle_statePubSubTypes.h"
#include "scene_descriptionPubSubTypes.h"
#include "scorePubSubTypes.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"
#include "tool_statePubSubTypes.h"

namespace microdex::instructor {
namespace {

namespace dds = eprosima::fastdds::dds;
using record::TopicIndex;

std::int64_t MonoNowNs() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// The files of a recorded station's scene found here (FindRecordedScene) that hash to its
// recorded scene_hash; nullopt with the reason otherwise.
std::optional<view::SceneFiles> RecordedSceneFiles(const msg::StationInfo& s,
                                                   const std::string& scene_dir, std::string* why) {
  const std::string recorded = s.scene().to_string();
  const std::string path = FindRecordedScene(recorded, scene_dir);
  if (path.empty()) {
    *why =
        "scene '" + recorded + "' not found" +
        (scene_dir.empty() ? " (give its folder with --scene-dir)" : " here nor in " + scene_dir);
    return std::nullopt;
  }
  try {
    view::SceneFiles files = view::CollectSceneFiles(scene::LoadScene(path));
    if (files.hash != s.scene_hash()) {
      *why = path + " is not the recorded scene (its files hash to " + view::HashHex(files.hash) +
             ", the recording's to " + view::HashHex(s.scene_hash()) + ")";
      return std::nullopt;
    }
    return files;
  } catch (const std::exception& e) {
    *why = path + ": " + e.what();
    return std::nullopt;
  }
}

// One writer per recorded topic; Publish decodes a recorded sample and writes it.
class Publishers {
 public:
  // `stations`: one DeviceInput writer each (the profile's writer holds one instance, as a
  // station's does).
  Publishers(net::DdsContext& context, const std::vector<std::string>& stations,
             std::string scene_dir)
      : dds_(context), scene_dir_(std::move(scene_dir)) {
    net::DdsContext& dds = context;
    for (const auto& s : stations) {
      inputs_[s] = dds.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceInputTopic);
    }
    info_ = dds.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
    writers_[TopicIndex::kStationInfo] = info_;
    writers_[TopicIndex::kToolState] =
        dds.CreateWriter<msg::ToolStatePubSubType>(net::kToolStateTopic);
    writers_[TopicIndex::kNeedleState] =
        dds.CreateWriter<msg::NeedleStatePubSubType>(net::kNeedleStateTopic);
    writers_[TopicIndex::kThreadState] =
        dds.CreateWriter<msg::ThreadStatePubSubType>(net::kThreadStateTopic);
    writers_[TopicIndex::kTissueState] =
        dds.CreateWriter<msg::TissueStatePubSubType>(net::kTissueStateTopic);
    writers_[TopicIndex::kTelemetry] =
        dds.CreateWriter<msg::TelemetryPubSubType>(net::kTelemetryTopic);
    writers_[TopicIndex::kCueCommand] =
        dds.CreateWriter<msg::CueCommandPubSubType>(net::kCueCommandTopic);
    writers_[TopicIndex::kTaskEvent] =
        dds.CreateWriter<msg::TaskEventPubSubType>(net::kTaskEventTopic);
    writers_[TopicIndex::kScore] = dds.CreateWriter<msg::ScorePubSubType>(net::kScoreTopic);
    writers_[TopicIndex::kCueOverlay] =
        dds.CreateWriter<msg::CueOverlayPubSubType>(net::kCueOverlayTopic);
  }

  // False when the bytes do not decode.
  bool Publish(const record::MessageView& m) {
    switch (static_cast<TopicIndex>(m.topic)) {
      case TopicIndex::kStationInfo: {
        msg::StationInfo s;
        if (!DecodeSample<msg::StationInfoPubSubType>(m.cdr, s)) return false;
        Describe(s);
        info_->write(&s);
        stations_[s.station_id().to_string()] = s;
        return true;
      }
      case TopicIndex::kDeviceInput: {
        const auto w = inputs_.find(std::string(m.station));
        msg::DeviceInput s;
        if (w == inputs_.end() || !DecodeSample<msg::DeviceInputPubSubType>(m.cdr, s)) return false;
        w->second->write(&s);
        return true;
      }
      case TopicIndex::kToolState:
        return Write<msg::ToolStatePubSubType, msg::ToolState>(m);
      case TopicIndex::kNeedleState:
        return Write<msg::NeedleStatePubSubType, msg::NeedleState>(m);
      case TopicIndex::kThreadState:
        return Write<msg::ThreadStatePubSubType, msg::ThreadState>(m);
      case TopicIndex::kTissueState:
        return Write<msg::TissueStatePubSubType, msg::TissueState>(m);
      case TopicIndex::kTelemetry:
        return Write<msg::TelemetryPubSubType, msg::Telemetry>(m);
      case TopicIndex::kCueCommand:
        return Write<msg::CueCommandPubSubType, msg::CueCommand>(m);
      case TopicIndex::kTaskEvent:
        return Write<msg::TaskEventPubSubType, msg::TaskEvent>(m);
      case TopicIndex::kScore:
        return Write<msg::ScorePubSubType, msg::Score>(m);
      case TopicIndex::kCueOverlay:
        return Write<msg::CueOverlayPubSubType, msg::CueOverlay>(m);
      case TopicIndex::kDeviceForce:
        return true;  // never republished: it would drive a real device (filtered out before)
    }
    return false;
  }

  // Waits until every writer has matched a reader (a console is listening), or the deadline
  // (monotonic ns) passes, or `stop`. True when all matched.
  bool WaitForReaders(std::int64_t deadline_ns, const std::atomic<bool>& stop) {
    std::vector<dds::DataWriter*> all;
    for (const auto& [t, w] : writers_) {
      // A console reads neither the cue commands nor (yet) the overlays.
      if (t != TopicIndex::kCueCommand && t != TopicIndex::kCueOverlay) all.push_back(w);
    }
    for (const auto& [s, w] : inputs_) all.push_back(w);
    for (;;) {
      bool matched = true;
      for (dds::DataWriter* w : all) {
        dds::PublicationMatchedStatus status;
        w->get_publication_matched_status(status);
        matched = matched && status.current_count > 0;
      }
      if (matched) return true;
      if (stop.load() || MonoNowNs() >= deadline_ns) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  // Once per station, before its first StationInfo: its scene's files, when found here with
  // the recorded hash.
  void Describe(const msg::StationInfo& s) {
    const std::string id = s.station_id().to_string();
    if (s.scene_hash() == 0 || !described_.insert(id).second) return;
    std::string why;
    const std::optional<view::SceneFiles> files = RecordedSceneFiles(s, scene_dir_, &why);
    if (!files) {
      scenes_missing_.push_back(id + ": " + why);
      return;
    }
    msg::SceneDescription d =
        view::ToSceneDescription(*files, id, s.session_id().to_string(), s.stamp_ns());
    if (scene_ == nullptr) {
      scene_ = dds_.CreateWriter<msg::SceneDescriptionPubSubType>(net::kSceneDescriptionTopic);
    }
    scene_->write(&d);
    scenes_sent_.push_back(id);
  }
  const std::vector<std::string>& scenes_sent() const { return scenes_sent_; }
  const std::vector<std::string>& scenes_missing() const { return scenes_missing_; }

  // After a seek: new StationInfo and DeviceInput writers, the old ones kept until
  // DropOldWriters (so that the stations' instances always have a writer: a console sees no
  // station lost). A console takes a StationInfo from another writer as a new run, and the
  // DeviceInput steps that follow as that run's, not as repeats.
  void RenewRunWriters() {
    old_.push_back(info_);
    for (auto& [s, w] : inputs_) {
      old_.push_back(w);
      w = dds_.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceInputTopic);
    }
    info_ = dds_.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
    writers_[TopicIndex::kStationInfo] = info_;
    stations_.clear();
  }
  // Once the new StationInfo writer's announcements are acknowledged (up to 1 s).
  void DropOldWriters() {
    info_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(1, 0));
    for (dds::DataWriter* w : old_) dds_.DeleteWriter(w);
    old_.clear();
  }

  // The replayed stations leave: their StationInfo instances are disposed.
  void DisposeStations() {
    for (auto& [id, s] : stations_) info_->dispose(&s, info_->lookup_instance(&s));
  }

 private:
  template <class PubSubType, class Msg>
  bool Write(const record::MessageView& m) {
    Msg s;
    if (!DecodeSample<PubSubType>(m.cdr, s)) return false;
    writers_[static_cast<TopicIndex>(m.topic)]->write(&s);
    return true;
  }

  dds::DataWriter* info_ = nullptr;
  std::map<TopicIndex, dds::DataWriter*> writers_;
  std::map<std::string, dds::DataWriter*> inputs_;  // by station
  std::vector<dds::DataWriter*> old_;               // replaced by a seek, not yet deleted
  std::map<std::string, msg::StationInfo> stations_;
  net::DdsContext& dds_;
  std::string scene_dir_;
  dds::DataWriter* scene_ = nullptr;  // SceneDescription, once a scene is found
  std::set<std::string> described_;
  std::vector<std::string> scenes_sent_, scenes_missing_;
};

}  // namespace

std::string FindRecordedScene(const std::string& recorded_path, const std::string& scene_dir) {
  std::error_code ec;
  if (!recorded_path.empty() && std::filesystem::is_regular_file(recorded_path, ec)) {
    return recorded_path;
  }
  if (scene_dir.empty() || recorded_path.empty()) return "";
  const std::string there =
      (std::filesystem::path(scene_dir) / std::filesystem::path(recorded_path).filename()).string();
  return std::filesystem::is_regular_file(there, ec) ? there : "";
}

std::vector<std::string> MissingRecordedScenes(record::SessionReader& reader,
                                               const std::string& scene_dir) {
  std::vector<std::string> out;
  std::set<std::string> seen;
  record::MessageFilter f;
  f.topic = static_cast<int>(TopicIndex::kStationInfo);
  reader.ForEach(f, [&](const record::MessageView& m) {
    msg::StationInfo s;
    if (!DecodeSample<msg::StationInfoPubSubType>(m.cdr, s)) return true;
    const std::string id = s.station_id().to_string();
    if (!seen.insert(id).second) return true;
    std::string why;
    if (s.scene_hash() == 0) {
      out.push_back(id + ": the recording names no scene files");
    } else if (!RecordedSceneFiles(s, scene_dir, &why)) {
      out.push_back(id + ": " + why);
    }
    return true;
  });
  return out;
}

PlayerClock::PlayerClock(std::int64_t session_start_ns, double speed, NowFn now)
    : now_(now ? now : &MonoNowNs),
      anchor_session_ns_(session_start_ns),
      anchor_wall_ns_(now_()),
      speed_(std::clamp(speed, 1.0 / 64, 1024.0)) {}

std::int64_t PlayerClock::SessionAtLocked(std::int64_t wall_ns) const {
  if (paused_) return anchor_session_ns_;
  return anchor_session_ns_ +
         static_cast<std::int64_t>(static_cast<double>(wall_ns - anchor_wall_ns_) * speed_);
}

std::int64_t PlayerClock::SessionNowNs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return SessionAtLocked(now_());
}

std::optional<std::int64_t> PlayerClock::WallTimeOf(std::int64_t session_ns) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (paused_) {
    if (session_ns <= anchor_session_ns_) return now_();
    return std::nullopt;
  }
  return anchor_wall_ns_ +
         static_cast<std::int64_t>(static_cast<double>(session_ns - anchor_session_ns_) / speed_);
}

void PlayerClock::Restart() {
  std::lock_guard<std::mutex> lock(mutex_);
  anchor_wall_ns_ = now_();
}

void PlayerClock::SetSpeed(double speed) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::int64_t now = now_();
  anchor_session_ns_ = SessionAtLocked(now);
  anchor_wall_ns_ = now;
  speed_ = std::clamp(speed, 1.0 / 64, 1024.0);
}

double PlayerClock::speed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return speed_;
}

void PlayerClock::TogglePause() {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::int64_t now = now_();
  anchor_session_ns_ = SessionAtLocked(now);
  anchor_wall_ns_ = now;
  paused_ = !paused_;
}

bool PlayerClock::paused() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return paused_;
}

void PlayerClock::Seek(std::int64_t session_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  anchor_session_ns_ = session_ns;
  anchor_wall_ns_ = now_();
  ++seeks_;
}

std::uint64_t PlayerClock::seeks() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seeks_;
}

void PlayerClock::Step(std::int64_t dt_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (paused_) anchor_session_ns_ += dt_ns;
}

PlayStats Play(record::SessionReader& reader, const net::DdsOptions& dds, const PlayOptions& o,
               PlayerClock& clock, const std::atomic<bool>& stop) {
  const auto [first_ns, last_ns] = reader.TimeRange();
  const std::int64_t from_ns =
      first_ns + (o.from_s ? static_cast<std::int64_t>(*o.from_s * 1e9) : 0);
  const std::int64_t to_ns = o.to_s ? first_ns + static_cast<std::int64_t>(*o.to_s * 1e9) : last_ns;
  net::DdsContext context(dds);
  Publishers pub(context, reader.Stations(), o.scene_dir);
  PlayStats stats;
  // A console that is listening gets the session from its start: wait for it to match (up to
  // wait_for_console_s), then restart the clock.
  if (o.wait_for_console_s > 0) {
    stats.console_found = pub.WaitForReaders(
        MonoNowNs() + static_cast<std::int64_t>(o.wait_for_console_s * 1e9), stop);
  }
  clock.Restart();
  std::int64_t from = from_ns;
  for (bool sought = false;;) {
    const std::uint64_t seeks = clock.seeks();
    // A replay that starts later than the beginning still announces every station first: the
    // latest StationInfo of each before `from`.
    // After a seek, the new writer announces them even at the session's start.
    if (from > first_ns || sought) {
      record::MessageFilter f;
      f.topic = static_cast<int>(TopicIndex::kStationInfo);
      f.to_ns = from;
      reader.ForEach(f, [&](const record::MessageView& m) {
        if (pub.Publish(m)) ++stats.published;
        return true;
      });
    }
    if (sought) pub.DropOldWriters();
    sought = false;
    record::MessageFilter f;
    f.from_ns = from;
    f.to_ns = to_ns;
    std::int64_t reached = from;
    reader.ForEach(f, [&](const record::MessageView& m) {
      if (m.topic == static_cast<int>(TopicIndex::kCueCommand) && !o.republish_cues) return true;
      if (m.topic == static_cast<int>(TopicIndex::kDeviceForce)) return true;  // drives a device
      // Wait until the clock reaches the message (sleeping in slices, so that pause, seek and
      // stop work).
      for (;;) {
        if (stop.load()) return false;
        if (clock.seeks() != seeks) {
          sought = true;
          return false;
        }
        const std::optional<std::int64_t> wall = clock.WallTimeOf(m.receive_ns);
        const std::int64_t now = clock.WallNowNs();
        if (wall && *wall <= now) break;
        const std::int64_t wait =
            wall ? std::min<std::int64_t>(*wall - now, 20'000'000) : 20'000'000;
        std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
      }
      if (pub.Publish(m)) {
        ++stats.published;
      } else {
        ++stats.undecodable;
      }
      reached = m.receive_ns;
      return true;
    });
    stats.session_s += static_cast<double>(reached - from) * 1e-9;
    if (!sought || stop.load()) break;
    ++stats.seeks;
    pub.RenewRunWriters();
    pub.WaitForReaders(MonoNowNs() + 2'000'000'000, stop);
    // Where the clock is now (the seek, and the little time the new writers took to match).
    from = std::clamp(clock.SessionNowNs(), first_ns, to_ns);
  }
  stats.scenes_sent = pub.scenes_sent();
  stats.scenes_missing = pub.scenes_missing();
  pub.DisposeStations();
  // Let reliable samples reach the readers before the participant goes.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  return stats;
}

}  // namespace microdex::instructor
