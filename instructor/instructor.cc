#include "instructor/instructor.h"

#include <spdlog/spdlog.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/LivelinessChangedStatus.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <unordered_map>
#include <utility>

#include "common/base/check.h"
#include "common/net/convert.h"
#include "common/net/overlay_convert.h"
#include "common/record/recorded_topics.h"
#include "cue_commandPubSubTypes.h"
#include "cue_overlayPubSubTypes.h"
#include "device_forcePubSubTypes.h"
#include "device_inputPubSubTypes.h"
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

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

std::int64_t RealtimeNowNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

std::string HandleKey(const eprosima::fastrtps::rtps::InstanceHandle_t& h) {
  const eprosima::fastrtps::rtps::octet* bytes = h.value;
  return std::string(reinterpret_cast<const char*>(bytes), 16);
}

// A remote writer's GUID as the 16 bytes of its instance handle (SampleInfo's
// publication_handle), a map key that needs no allocation.
using WriterKey = std::array<std::uint8_t, 16>;
WriterKey KeyOf(const eprosima::fastrtps::rtps::InstanceHandle_t& h) {
  WriterKey k;
  std::memcpy(k.data(), h.value, k.size());
  return k;
}
struct WriterKeyHash {
  std::size_t operator()(const WriterKey& k) const {
    std::uint64_t a = 0, b = 0;  // the prefix's last bytes and the entity id differ most
    std::memcpy(&a, k.data(), 8);
    std::memcpy(&b, k.data() + 8, 8);
    return std::hash<std::uint64_t>()(a * 0x9e3779b97f4a7c15ULL ^ b);
  }
};

// The partitions of every remote writer as discovery reported them. Fast DDS calls
// on_publisher_discovery on its discovery thread when it adds the writer's proxy, before it
// pairs the writer with a reader, so before any sample of it can be taken.
// (DataReader::get_matched_publication_data, the standard way, returns RETCODE_UNSUPPORTED in
// Fast DDS 2.9.) A removed writer is kept for kRemovedKeep_ns: its last samples (a final
// score, a StationInfo disposal) may still wait in a reader.
class WriterPartitions final : public dds::DomainParticipantListener {
 public:
  static constexpr std::int64_t kRemovedKeep_ns = 60'000'000'000;

  void on_publisher_discovery(dds::DomainParticipant* /*participant*/,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    using Info = eprosima::fastrtps::rtps::WriterDiscoveryInfo;
    const WriterKey key = KeyOf(eprosima::fastrtps::rtps::InstanceHandle_t(info.info.guid()));
    const std::int64_t now = MonotonicNowNs();
    std::lock_guard<std::mutex> lock(mutex_);
    if (info.status == Info::REMOVED_WRITER) {
      removed_.emplace_back(now, key);
    } else {
      writers_[key] = info.info.m_qos.m_partition.names();
      // A changed QoS may have changed the partition: the DDS thread's copies are stale.
      if (info.status == Info::CHANGED_QOS_WRITER) ++changes_;
    }
    while (!removed_.empty() && now - removed_.front().first > kRemovedKeep_ns) {
      writers_.erase(removed_.front().second);
      removed_.pop_front();
    }
  }

  // The writer's partitions; false when discovery never reported it.
  bool Find(const WriterKey& key, std::vector<std::string>* partitions) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = writers_.find(key);
    if (it == writers_.end()) return false;
    *partitions = it->second;
    return true;
  }
  std::uint64_t changes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return changes_;
  }

 private:
  mutable std::mutex mutex_;
  std::unordered_map<WriterKey, std::vector<std::string>, WriterKeyHash> writers_;
  std::deque<std::pair<std::int64_t, WriterKey>> removed_;
  std::uint64_t changes_ = 0;
};

}  // namespace

std::int64_t MonotonicNowNs() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

const char* PresenceName(Presence p) {
  switch (p) {
    case Presence::kAlive:
      return "alive";
    case Presence::kLost:
      return "LOST";
    case Presence::kDeparted:
      return "left";
  }
  return "?";
}

struct Instructor::Dds {
  // Per-station partitions (the secure instructor's COURSE/*): "COURSE/", the prefix of every
  // station's partition; empty otherwise (no check). Declared before the context, which
  // calls the listener until it is destroyed.
  std::string station_partition_prefix;
  WriterPartitions writer_partitions;
  // The DDS thread's copy: the station each writer may speak for ("" none), by writer.
  std::unordered_map<WriterKey, std::string, WriterKeyHash> writer_station;
  std::uint64_t writer_changes_seen = 0;
  std::vector<std::string> partitions_scratch;
  std::unique_ptr<net::DdsContext> context;
  dds::DataReader* info = nullptr;
  dds::DataReader* input = nullptr;
  dds::DataReader* tool = nullptr;
  dds::DataReader* needle = nullptr;
  dds::DataReader* thread = nullptr;
  dds::DataReader* tissue = nullptr;
  dds::DataReader* telemetry = nullptr;
  dds::DataReader* events = nullptr;
  dds::DataReader* score = nullptr;
  dds::DataReader* scene = nullptr;    // SceneDescription
  dds::DataReader* overlay = nullptr;  // CueOverlay (the console's mirror, and recorded)
  dds::DataReader* force = nullptr;    // DeviceForce: recording only (nullptr without one)
  dds::DataWriter* cue = nullptr;
  dds::WaitSet waitset;
  dds::GuardCondition guard;
  std::map<std::string, std::string> instance_to_station;  // StationInfo instance → id
  // Station id → its current run's StationInfo writer: the departure or loss of an earlier
  // run's writer (a station restarted under the same id) does not end the current run.
  std::map<std::string, std::string> current_info_writer;
  // Recording: one type support per recorded topic (record::TopicIndex order) to serialize
  // the samples again, and one payload buffer reused for every sample.
  std::vector<std::unique_ptr<dds::TopicDataType>> types;
  eprosima::fastrtps::rtps::SerializedPayload_t payload;
  std::uint64_t record_failed = 0;
};

Instructor::Instructor(const InstructorOptions& options)
    : options_(options), dds_(std::make_unique<Dds>()) {
  session_id_ = (options_.issuer + "-" + std::to_string(RealtimeNowNs() / 1'000'000) + "-" +
                 std::to_string(getpid()))
                    .substr(0, 64);
  Dds& d = *dds_;
  ready_ = options_.recording_ready || !options_.record_file.empty();
  if (ready_) {
    d.types.emplace_back(new msg::StationInfoPubSubType());
    d.types.emplace_back(new msg::DeviceInputPubSubType());
    d.types.emplace_back(new msg::ToolStatePubSubType());
    d.types.emplace_back(new msg::NeedleStatePubSubType());
    d.types.emplace_back(new msg::ThreadStatePubSubType());
    d.types.emplace_back(new msg::TissueStatePubSubType());
    d.types.emplace_back(new msg::TelemetryPubSubType());
    d.types.emplace_back(new msg::CueCommandPubSubType());
    d.types.emplace_back(new msg::TaskEventPubSubType());
    d.types.emplace_back(new msg::ScorePubSubType());
    d.types.emplace_back(new msg::CueOverlayPubSubType());
    d.types.emplace_back(new msg::DeviceForcePubSubType());
    for (int i = 0; i < record::kTopicCount; ++i) {
      MICRODEX_CHECK(d.types[static_cast<std::size_t>(i)]->getName() ==
                     record::KnownTopics()[static_cast<std::size_t>(i)].type);
    }
  }
  if (!options_.record_file.empty()) StartRecording(options_.record_file);
  net::DdsOptions dds_options = options_.dds;
  dds_options.participant_listener = &d.writer_partitions;
  d.context = std::make_unique<net::DdsContext>(dds_options);
  if (const std::string& part = d.context->partition(); part.ends_with("/*")) {
    d.station_partition_prefix = part.substr(0, part.size() - 1);
  }
  d.info = d.context->CreateReader<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  // Recording: readers that keep every sample until it is taken (net::RecordingReaderSpec).
  const auto spec = [&](const net::TopicSpec& s) {
    return ready_ ? net::RecordingReaderSpec(s) : s;
  };
  if (ready_ || options_.receive_inputs) {
    d.input = d.context->CreateReader<msg::DeviceInputPubSubType>(spec(net::kDeviceInputTopic));
  }
  d.tool = d.context->CreateReader<msg::ToolStatePubSubType>(spec(net::kToolStateTopic));
  d.needle = d.context->CreateReader<msg::NeedleStatePubSubType>(spec(net::kNeedleStateTopic));
  d.thread = d.context->CreateReader<msg::ThreadStatePubSubType>(spec(net::kThreadStateTopic));
  d.tissue = d.context->CreateReader<msg::TissueStatePubSubType>(spec(net::kTissueStateTopic));
  d.telemetry = d.context->CreateReader<msg::TelemetryPubSubType>(spec(net::kTelemetryTopic));
  d.events = d.context->CreateReader<msg::TaskEventPubSubType>(net::kTaskEventTopic);
  d.score = d.context->CreateReader<msg::ScorePubSubType>(net::kScoreTopic);
  d.scene = d.context->CreateReader<msg::SceneDescriptionPubSubType>(net::kSceneDescriptionTopic);
  d.overlay = d.context->CreateReader<msg::CueOverlayPubSubType>(spec(net::kCueOverlayTopic));
  d.cue = d.context->CreateWriter<msg::CueCommandPubSubType>(net::kCueCommandTopic);
  if (ready_) {
    // DeviceForce: the bridge's writer is best-effort and latest-only; read with a deep
    // best-effort history so that none is replaced before it is taken.
    net::TopicSpec force = net::kDeviceForceTopic;
    force.reader_profile = "microdex_force_record_reader";
    d.force = d.context->CreateReader<msg::DeviceForcePubSubType>(force);
  }
  for (dds::DataReader* r : {d.info, d.input, d.tool, d.needle, d.thread, d.tissue, d.telemetry,
                             d.events, d.score, d.scene, d.overlay, d.force}) {
    if (r == nullptr) continue;
    dds::StatusMask mask = dds::StatusMask::data_available();
    if (r == d.info) mask << dds::StatusMask::liveliness_changed();
    r->get_statuscondition().set_enabled_statuses(mask);
    d.waitset.attach_condition(r->get_statuscondition());
  }
  d.waitset.attach_condition(d.guard);
  thread_ = std::thread([this] { Run(); });
}

Instructor::~Instructor() {
  stop_ = true;
  dds_->guard.set_trigger_value(true);
  if (thread_.joinable()) thread_.join();
  RecordRejected(true);  // the final counts (the recorder writes them as it stops)
  Dds& d = *dds_;
  d.waitset.detach_condition(d.guard);
  for (dds::DataReader* r : {d.info, d.input, d.tool, d.needle, d.thread, d.tissue, d.telemetry,
                             d.events, d.score, d.scene, d.overlay, d.force}) {
    if (r != nullptr) d.waitset.detach_condition(r->get_statuscondition());
  }
  d.context.reset();
}

const char* LossSignalName(LossSignal s) {
  switch (s) {
    case LossSignal::kNone:
      return "none";
    case LossSignal::kLiveliness:
      return "liveliness";
    case LossSignal::kNoWriters:
      return "no-writers";
    case LossSignal::kSilence:
      return "silence";
  }
  return "?";
}

void Instructor::MarkLost(StationView& v, LossSignal signal, std::int64_t now_ns) {
  if (v.presence != Presence::kAlive) return;
  v.presence = Presence::kLost;
  v.presence_changed_ns = now_ns;
  v.lost_by = signal;
}

void Instructor::Heard(StationView& v, std::int64_t now_ns) {
  v.last_heard_ns = now_ns;
  if (v.presence == Presence::kLost &&
      (v.lost_by == LossSignal::kSilence || v.lost_by == LossSignal::kLiveliness)) {
    // Its data resumed within the DDS lease (a network partition, not a dead station: its
    // writers are still matched, so its StationInfo is not sent again).
    v.presence = Presence::kAlive;
    v.presence_changed_ns = now_ns;
    ++v.comebacks;
  }
}

void Instructor::Reject(const char* topic, const std::string& why) {
  ++rejected_.by_topic[topic];
  ++rejected_.total;
  rejected_.last_reason = std::string(topic) + ": " + why;
}

bool Instructor::FromItsStation(const void* sample_info, const char* station_id, const char* topic,
                                bool second_device_key) {
  Dds& d = *dds_;
  if (d.station_partition_prefix.empty()) return true;  // no per-station partitions
  const auto& si = *static_cast<const dds::SampleInfo*>(sample_info);
  if (const std::uint64_t changes = d.writer_partitions.changes();
      changes != d.writer_changes_seen || d.writer_station.size() > kMaxWriterCache) {
    d.writer_station.clear();
    d.writer_changes_seen = changes;
  }
  const WriterKey key = KeyOf(si.publication_handle);
  auto it = d.writer_station.find(key);
  if (it == d.writer_station.end()) {
    // Once per writer: the station its partition names ("" when it names none, or several).
    std::string station;
    if (d.writer_partitions.Find(key, &d.partitions_scratch) && d.partitions_scratch.size() == 1) {
      const std::string& p = d.partitions_scratch.front();
      if (p.size() > d.station_partition_prefix.size() &&
          p.starts_with(d.station_partition_prefix) &&
          p.find_first_of("*?[]\\", d.station_partition_prefix.size()) == std::string::npos) {
        station = p.substr(d.station_partition_prefix.size());
      }
    }
    it = d.writer_station.emplace(key, std::move(station)).first;
  }
  const std::string& allowed = it->second;
  const std::size_t n = std::strlen(station_id);
  if (!allowed.empty() && n >= allowed.size() &&
      std::memcmp(station_id, allowed.data(), allowed.size()) == 0 &&
      (n == allowed.size() ||
       (second_device_key && std::strcmp(station_id + allowed.size(), "/2") == 0))) {
    return true;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  std::string named(station_id, std::min<std::size_t>(n, 64));
  for (char& ch : named) {
    if (ch < ' ' || ch > '~') ch = '?';  // quoted in tables and pages
  }
  Reject(topic,
         allowed.empty()
             ? "station_id '" + named + "' from a writer in no station's partition"
             : "station_id '" + named + "' from a writer in the partition of '" + allowed + "'");
  return false;
}

bool Instructor::Admit(const std::string& station_id, const char* topic) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stations_.count(station_id) > 0 || stations_.size() < kMaxStations) return true;
  Reject(topic, "station_id: a new station beyond the " + std::to_string(kMaxStations) +
                    " the registry admits");
  return false;
}

StationView& Instructor::ViewFor(const std::string& station_id) {
  auto it = stations_.find(station_id);
  if (it == stations_.end()) {
    it = stations_.emplace(station_id, StationView{}).first;
    it->second.info.header.station_id = station_id;
    it->second.presence_changed_ns = MonotonicNowNs();
    it->second.inputs_taken = dds_->input != nullptr;
  }
  return it->second;
}

void Instructor::Run() {
  dds::ConditionSeq active;
  while (!stop_.load()) {
    // A backlog left by the last pass is taken at once; otherwise wait for data.
    if (!std::exchange(backlog_, false)) {
      dds_->waitset.wait(active, eprosima::fastrtps::Duration_t(0, 200'000'000));
    }
    if (stop_.load()) break;
    dds_->guard.set_trigger_value(false);
    SendQueuedCues();
    // Liveliness first: when a station's participant is dropped, its liveliness change and
    // its instance's NOT_ALIVE_NO_WRITERS arrive together, and the former names the signal.
    HandleLiveliness();
    HandleStationInfo();
    HandleInputs();
    TakeAll<msg::ToolState, net::ToolState>(dds_->tool, &StationView::tool, "tool_state");
    TakeAll<msg::NeedleState, net::NeedleState>(dds_->needle, &StationView::needle, "needle_state");
    TakeAll<msg::ThreadState, net::ThreadState>(dds_->thread, &StationView::thread, "thread_state");
    TakeAll<msg::TissueState, net::TissueState>(dds_->tissue, &StationView::tissue, "tissue_state");
    TakeAll<msg::Telemetry, net::Telemetry>(dds_->telemetry, &StationView::telemetry, "telemetry");
    HandleEvents();
    HandleScores();
    HandleSceneDescriptions();
    HandleOverlays();
    RecordOnly<msg::DeviceForce>(dds_->force, record::TopicIndex::kDeviceForce, "device_force");
    CheckSilence();
    RecordRejected(false);
  }
}

// One pass of Run() takes at most this many samples of each reader, so that a flood on one
// topic (8 stations' 1 kHz DeviceInput on a starved host) never holds the others back past
// their writers' history (the mirrored states keep 4 s: a longer wait is a sequence gap in a
// recording). The rest are taken on the next pass, which comes at once.
constexpr int kTakeBatch = 256;

bool Instructor::TakeNext(void* reader, void* m, void* si, int& taken) {
  if (taken == kTakeBatch) {
    backlog_ = true;
    return false;
  }
  ++taken;
  return static_cast<dds::DataReader*>(reader)->take_next_sample(
             m, static_cast<dds::SampleInfo*>(si)) == ReturnCode_t::RETCODE_OK;
}

void Instructor::CheckSilence() {
  const std::int64_t now = MonotonicNowNs();
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [id, v] : stations_) {
    if (v.presence != Presence::kAlive || v.last_heard_ns == 0) continue;
    if (now - v.last_heard_ns > kSilenceLimit_ns) MarkLost(v, LossSignal::kSilence, now);
  }
}

void Instructor::HandleStationInfo() {
  msg::StationInfo m;
  dds::SampleInfo si;
  for (int taken = 0; TakeNext(dds_->info, &m, &si, taken);) {
    net::StationInfo info;
    if (si.valid_data) {
      if (!FromItsStation(&si, m.station_id().c_str(), "station_info")) continue;
      std::string why;
      if (!net::FromMsg(m, info, &why)) {
        std::lock_guard<std::mutex> lock(mutex_);
        Reject("station_info", why);
        continue;
      }
      if (!Admit(info.header.station_id, "station_info")) continue;
      Record(static_cast<int>(record::TopicIndex::kStationInfo), m, &si);
    }
    std::string disposed_station;  // the station of a disposed or writerless instance
    if (!si.valid_data) {
      // dds_->instance_to_station: the DDS thread's own (written below, under mutex_ only
      // because the registry is).
      auto it = dds_->instance_to_station.find(HandleKey(si.instance_handle));
      if (it == dds_->instance_to_station.end()) continue;
      // Only the station's own writer may announce its departure.
      if (si.instance_state == dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE &&
          !FromItsStation(&si, it->second.c_str(), "station_info")) {
        continue;
      }
      disposed_station = it->second;
    }
    const std::int64_t now = MonotonicNowNs();
    std::lock_guard<std::mutex> lock(mutex_);
    if (si.valid_data) {
      dds_->instance_to_station[HandleKey(si.instance_handle)] = info.header.station_id;
      writer_to_station_[HandleKey(si.publication_handle)] = info.header.station_id;
      std::string& current = dds_->current_info_writer[info.header.station_id];
      StationView& v = ViewFor(info.header.station_id);
      if (current != HandleKey(si.publication_handle)) {
        // Another writer: a new run or a replay of a recorded one (which may repeat the steps
        // of a run seen before, under its session id). The same writer announcing again after
        // a partition keeps the steps it sent, so that those it resends are dropped.
        v.input_session.clear();
        current = HandleKey(si.publication_handle);
      }
      const bool known = v.info.header.session_id.size() > 0;
      if (known && v.presence != Presence::kAlive) ++v.comebacks;
      if (v.presence != Presence::kAlive || !known) v.presence_changed_ns = now;
      v.presence = Presence::kAlive;
      v.last_heard_ns = now;
      v.info = std::move(info);
      continue;
    }
    if (si.instance_state == dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE &&
        dds_->current_info_writer[disposed_station] != HandleKey(si.publication_handle)) {
      continue;  // an earlier run's departure, arriving after the current run's StationInfo
    }
    StationView& v = ViewFor(disposed_station);
    if (si.instance_state == dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE) {
      if (v.presence != Presence::kDeparted) v.presence_changed_ns = now;
      v.presence = Presence::kDeparted;
    } else if (si.instance_state == dds::NOT_ALIVE_NO_WRITERS_INSTANCE_STATE) {
      MarkLost(v, LossSignal::kNoWriters, now);
    }
  }
}

void Instructor::HandleLiveliness() {
  dds::LivelinessChangedStatus status;
  dds_->info->get_liveliness_changed_status(status);
  // A StationInfo writer missed its lease (not_alive grows) or vanished with its participant
  // (alive shrinks: Fast DDS 2.9 reports a SIGKILLed station this way, when the participant
  // lease of 1 s expires). The status names the last writer that changed; the instance state
  // (NOT_ALIVE_NO_WRITERS, HandleStationInfo) covers stations that fail together, and the
  // silence watchdog (CheckSilence) is the last resort.
  if (status.not_alive_count_change <= 0 && status.alive_count_change >= 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string writer = HandleKey(status.last_publication_handle);
  auto it = writer_to_station_.find(writer);
  if (it == writer_to_station_.end()) return;
  // An earlier run's writer gone (a station restarted under the same id): not this run's loss.
  if (dds_->current_info_writer[it->second] != writer) return;
  MarkLost(ViewFor(it->second), LossSignal::kLiveliness, MonotonicNowNs());
}

template <class Msg>
void Instructor::Record(int topic, Msg& m, const void* sample_info) {
  // StationInfo is kept even while not recording: a recording begun later starts with it.
  const bool info = topic == static_cast<int>(record::TopicIndex::kStationInfo);
  if (!ready_ || (!info && !recording_.load(std::memory_order_relaxed))) return;
  const auto& si = *static_cast<const dds::SampleInfo*>(sample_info);
  Dds& d = *dds_;
  dds::TopicDataType& type = *d.types[static_cast<std::size_t>(topic)];
  const std::uint32_t size = type.getSerializedSizeProvider(&m)();
  if (d.payload.max_size < size) d.payload.reserve(size);
  d.payload.length = 0;
  d.payload.pos = 0;
  if (!type.serialize(&m, &d.payload)) {
    ++d.record_failed;
    return;
  }
  record::RecordedMessage r;
  r.topic = topic;
  r.station = m.station_id();
  r.session = m.session_id();
  r.receive_ns = RealtimeNowNs();
  r.source_ns = si.source_timestamp.to_ns();
  r.sequence = si.sample_identity.sequence_number().to64long();
  r.step = m.step();
  r.cdr.assign(d.payload.data, d.payload.data + d.payload.length);
  std::lock_guard<std::mutex> lock(recorder_mutex_);
  if (info) latest_info_[r.station] = r;
  if (recorder_) recorder_->Push(std::move(r));
}

template <class Msg, class Plain>
void Instructor::TakeAll(void* reader_ptr, Mirror<Plain> StationView::*mirror, const char* topic) {
  auto* reader = static_cast<dds::DataReader*>(reader_ptr);
  Msg m;
  dds::SampleInfo si;
  for (int taken = 0; TakeNext(reader, &m, &si, taken);) {
    if (!si.valid_data || !FromItsStation(&si, m.station_id().c_str(), topic)) continue;
    Plain p;
    std::string why;
    if (!net::FromMsg(m, p, &why)) {
      std::lock_guard<std::mutex> lock(mutex_);
      Reject(topic, why);
      continue;
    }
    if (!Admit(p.header.station_id, topic)) continue;
    Record(record::FindTopic(reader->get_topicdescription()->get_name()), m, &si);
    const std::int64_t now = MonotonicNowNs();
    const std::int64_t now_rt = RealtimeNowNs();
    std::lock_guard<std::mutex> lock(mutex_);
    StationView& v = ViewFor(p.header.station_id);
    if (options_.record_latency) {
      const double age_us = static_cast<double>(now_rt - p.header.stamp_ns) * 1e-3;
      latency_.state_age_us.push_back(age_us);
      latency_.state_age_us_by_topic[topic].push_back(age_us);
      latency_.transport_us.push_back(static_cast<double>(now_rt - si.source_timestamp.to_ns()) *
                                      1e-3);
    }
    Heard(v, now);
    if constexpr (std::is_same_v<Plain, net::Score>) {
      // For the scores database (a few per station run; bounded for a console without one).
      if (p.is_final && final_scores_.size() < 10000) final_scores_.push_back(p);
    }
    Mirror<Plain>& mir = v.*mirror;
    mir.latest = std::move(p);
    mir.received_ns = now;
    ++mir.count;
  }
}

template <class Msg>
void Instructor::RecordOnly(void* reader_ptr, record::TopicIndex topic, const char* name) {
  auto* reader = static_cast<dds::DataReader*>(reader_ptr);
  if (reader == nullptr) return;
  Msg m;
  dds::SampleInfo si;
  for (int taken = 0; TakeNext(reader, &m, &si, taken);) {
    // DeviceForce: a bimanual station's second device writes under STATION/2.
    if (si.valid_data && FromItsStation(&si, m.station_id().c_str(), name,
                                        /*second_device_key=*/true)) {
      Record(static_cast<int>(topic), m, &si);
    }
  }
}

void Instructor::HandleInputs() {
  msg::DeviceInput m;
  dds::SampleInfo si;
  net::DeviceInput p;
  if (dds_->input == nullptr) return;  // not taken (InstructorOptions::receive_inputs)
  for (int taken = 0; TakeNext(dds_->input, &m, &si, taken);) {
    if (!si.valid_data || !FromItsStation(&si, m.station_id().c_str(), "device_input")) continue;
    std::string why;
    if (!net::FromMsg(m, p, &why)) {
      std::lock_guard<std::mutex> lock(mutex_);
      Reject("device_input", why);
      continue;
    }
    if (!Admit(p.header.station_id, "device_input")) continue;
    std::unique_lock<std::mutex> lock(mutex_);
    StationView& v = ViewFor(p.header.station_id);
    if (v.input_session == p.header.session_id && p.header.step <= v.last_input_step) {
      // A step already taken: sent again after a station's writer matched this reader anew
      // (a partition around the lease), or a replayed sample. Recorded once only.
      Reject("device_input", "step " + std::to_string(p.header.step) + " already received");
      continue;
    }
    lock.unlock();
    Record(static_cast<int>(record::TopicIndex::kDeviceInput), m, &si);
    lock.lock();
    ++v.inputs_received;
    Heard(v, MonotonicNowNs());
    if (v.input_session != p.header.session_id) {
      v.input_session = p.header.session_id;  // a new run: no gap before its first sample
    } else if (p.header.step > v.last_input_step + 1) {
      // Steps missing (a partition longer than the lease dropped the match): counted, and
      // marked in the recording.
      v.inputs_lost += p.header.step - v.last_input_step - 1;
      gaps_.push_back({p.header.station_id, p.header.session_id, v.last_input_step + 1,
                       p.header.step - 1, RealtimeNowNs()});
      if (const auto rec = CurrentRecorder()) {
        rec->SetMetadata("input_gaps",
                         FormatInputGaps(gaps_, recording_started_realtime_ns_.load()));
      }
    }
    v.last_input_step = p.header.step;
  }
}

void Instructor::HandleEvents() {
  msg::TaskEvent m;
  dds::SampleInfo si;
  for (int taken = 0; TakeNext(dds_->events, &m, &si, taken);) {
    if (!si.valid_data || !FromItsStation(&si, m.station_id().c_str(), "task_event")) continue;
    net::TaskEvent e;
    std::string why;
    if (!net::FromMsg(m, e, &why)) {
      std::lock_guard<std::mutex> lock(mutex_);
      Reject("task_event", why);
      continue;
    }
    if (!Admit(e.header.station_id, "task_event")) continue;
    Record(static_cast<int>(record::TopicIndex::kTaskEvent), m, &si);
    std::lock_guard<std::mutex> lock(mutex_);
    StationView& v = ViewFor(e.header.station_id);
    Heard(v, MonotonicNowNs());
    v.events.push_back(e);
    if (v.events.size() > kMaxEventsPerStation) v.events.pop_front();
    new_events_.push_back(std::move(e));
  }
}

void Instructor::HandleScores() {
  TakeAll<msg::Score, net::Score>(dds_->score, &StationView::score, "score");
}

void Instructor::SendQueuedCues() {
  std::vector<net::CueCommand> cues;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    cues.swap(queued_cues_);
  }
  msg::CueCommand m;
  for (const auto& c : cues) {
    net::ToMsg(c, m);
    dds_->cue->write(&m);
    // The cue as sent (receive and source time: when it was written; sequence: its cue id).
    dds::SampleInfo si;
    si.source_timestamp =
        eprosima::fastrtps::Time_t(static_cast<std::int32_t>(c.header.stamp_ns / 1'000'000'000),
                                   static_cast<std::uint32_t>(c.header.stamp_ns % 1'000'000'000));
    si.sample_identity.sequence_number(
        eprosima::fastrtps::rtps::SequenceNumber_t(static_cast<std::uint64_t>(c.cue_id)));
    Record(static_cast<int>(record::TopicIndex::kCueCommand), m, &si);
  }
}

std::uint64_t Instructor::SendCue(const std::string& station_id, cues::CueKind kind, double param,
                                  std::uint64_t at_step, bool off) {
  if (station_id.empty() || station_id.size() > net::kMaxIdLength) {
    throw std::invalid_argument("cue target: expected a station id or 'all'");
  }
  net::CueCommand c;
  c.header = {station_id, session_id_, at_step, RealtimeNowNs()};
  c.cue_id = next_cue_id_++;
  c.kind = kind;
  c.param = param;
  c.off = off;
  c.issuer = options_.issuer.substr(0, net::kMaxIdLength);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queued_cues_.push_back(c);
  }
  dds_->guard.set_trigger_value(true);
  return c.cue_id;
}

std::vector<std::uint64_t> Instructor::SendCondition(const std::string& station_id,
                                                     const std::string& station_session,
                                                     const std::vector<cues::CueArg>& cues) {
  if (station_id.empty() || station_id == net::kAllStations ||
      station_id.size() > net::kMaxIdLength) {
    throw std::invalid_argument("condition target: expected a station id");
  }
  if (station_session.empty() || station_session.size() > net::kMaxIdLength) {
    throw std::invalid_argument("condition target: expected the station's session id");
  }
  if (cues.size() > net::kMaxConditionSize) {
    throw std::invalid_argument("condition: more than " + std::to_string(net::kMaxConditionSize) +
                                " cues");
  }
  std::vector<cues::CueArg> commands = cues;
  if (commands.empty()) commands.push_back({cues::CueKind::kClear, 0, false});  // "no cue"
  std::vector<std::uint64_t> ids;
  std::vector<net::CueCommand> out;
  for (const cues::CueArg& a : commands) {
    net::CueCommand c;
    c.header = {station_id, session_id_, 0, RealtimeNowNs()};
    c.cue_id = next_cue_id_++;
    c.kind = a.kind;
    c.param = a.off ? 0.0 : a.param;
    c.off = a.off;
    c.issuer = options_.issuer.substr(0, net::kMaxIdLength);
    c.station_session = station_session;
    c.condition_size = static_cast<std::uint32_t>(commands.size());
    ids.push_back(c.cue_id);
    out.push_back(std::move(c));
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queued_cues_.insert(queued_cues_.end(), out.begin(), out.end());
  }
  dds_->guard.set_trigger_value(true);
  return ids;
}

std::shared_ptr<record::Recorder> Instructor::CurrentRecorder() const {
  std::lock_guard<std::mutex> lock(recorder_mutex_);
  return recorder_;
}

std::optional<record::RecorderStats> Instructor::RecorderStats() const {
  const auto rec = CurrentRecorder();
  if (!rec) return std::nullopt;
  return rec->stats();
}

void Instructor::RecordRejected(bool now) {
  const auto rec = CurrentRecorder();
  if (!rec) return;
  const std::int64_t t = MonotonicNowNs();
  std::lock_guard<std::mutex> lock(mutex_);
  if (rejected_.total == rejected_recorded_ || (!now && t < next_rejected_record_ns_)) return;
  rejected_recorded_ = rejected_.total;
  next_rejected_record_ns_ = t + kRejectedRecordPeriod_ns;
  rec->SetMetadata("rejected_samples", FormatRejectedMetadata(rejected_));
  rec->SetMetadata("rejected_latest", rejected_.last_reason);
}

void Instructor::FlushRecording() {
  const auto rec = CurrentRecorder();
  if (!rec) return;
  RecordRejected(true);
  rec->Flush();
}

void Instructor::StartRecording(const std::string& path) {
  if (!ready_) {
    throw std::logic_error(
        "record: this console was not started ready to record (microdex-instructor "
        "--record-dir DIR or --record FILE)");
  }
  if (recording_.load()) {
    throw std::logic_error("record: already recording to " + RecordingPath());
  }
  // The file is made here, on the caller's thread (the DDS thread never waits for a disk).
  auto rec = std::make_shared<record::Recorder>(
      path,
      std::map<std::string, std::string>{{"recorder_session", session_id_},
                                         {"issuer", options_.issuer},
                                         {"dds_domain", std::to_string(options_.dds.domain_id)},
                                         {"dds_partition", options_.dds.partition}},
      options_.recorder);
  std::vector<std::string> alive;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, v] : stations_) {
      if (v.presence == Presence::kAlive) alive.push_back(id);
    }
    rejected_recorded_ = 0;  // the counts so far go into the new file too
    next_rejected_record_ns_ = 0;
  }
  const std::int64_t now_realtime = RealtimeNowNs();
  std::lock_guard<std::mutex> lock(recorder_mutex_);
  if (recorder_) throw std::logic_error("record: already recording to " + recorder_->path());
  // The stations alive now are announced first, as received, at the recording's start.
  for (const std::string& id : alive) {
    const auto it = latest_info_.find(id);
    if (it == latest_info_.end()) continue;
    record::RecordedMessage m = it->second;
    m.receive_ns = now_realtime;
    rec->Push(std::move(m));
  }
  recorder_ = std::move(rec);
  recording_started_ns_ = MonotonicNowNs();
  recording_started_realtime_ns_ = now_realtime;
  recording_.store(true);
}

std::optional<record::RecorderStats> Instructor::StopRecording() {
  if (!CurrentRecorder()) return std::nullopt;
  RecordRejected(true);
  std::shared_ptr<record::Recorder> rec;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::lock_guard<std::mutex> rlock(recorder_mutex_);
    if (!recorder_) return std::nullopt;
    rec = std::move(recorder_);
    recorder_.reset();
    recording_.store(false);
    rec->SetMetadata("input_gaps", FormatInputGaps(gaps_, recording_started_realtime_ns_.load()));
  }
  rec->Flush();
  return rec->stats();  // the file closes with the last reference
}

std::string Instructor::RecordingPath() const {
  const auto rec = CurrentRecorder();
  return rec ? rec->path() : "";
}

std::int64_t Instructor::RecordingStartedNs() const {
  std::lock_guard<std::mutex> lock(recorder_mutex_);
  return recorder_ ? recording_started_ns_.load() : 0;
}

std::vector<StationView> Instructor::Stations() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StationView> out;
  for (const auto& [id, v] : stations_) out.push_back(v);
  return out;
}

void Instructor::VisitStations(const std::function<void(const StationView&)>& f) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [id, v] : stations_) f(v);
}

// A station's scene as files: checked (sizes, paths, hash) before it is kept; a refused one is
// logged with the reason and kept as the station's scene_error (the console shows it).
void Instructor::HandleSceneDescriptions() {
  msg::SceneDescription m;
  dds::SampleInfo si;
  for (int taken = 0; TakeNext(dds_->scene, &m, &si, taken);) {
    if (!si.valid_data || !FromItsStation(&si, m.station_id().c_str(), "scene_description")) {
      continue;
    }
    const std::string station = m.station_id().to_string();
    if (station.empty() || std::any_of(station.begin(), station.end(),
                                       [](char ch) { return ch <= ' ' || ch > '~'; })) {
      std::lock_guard<std::mutex> lock(mutex_);
      Reject("scene_description", "station_id: empty or not printable ASCII");
      continue;
    }
    auto files = std::make_shared<view::SceneFiles>();
    files->scene_path = m.scene_path();
    files->hash = m.hash();
    std::string why;
    if (m.files().size() > view::kMaxSceneFiles) {
      why = std::to_string(m.files().size()) + " files, more than " +
            std::to_string(view::kMaxSceneFiles);
    } else {
      files->files.reserve(m.files().size());
      for (const msg::SceneFile& f : m.files()) {
        if (f.bytes().size() > view::kMaxSceneFileBytes) break;  // CheckSceneFiles names it
        files->files.push_back({f.path(), std::string(f.bytes().begin(), f.bytes().end())});
      }
      if (files->files.size() != m.files().size()) {
        why = "a file larger than " + std::to_string(view::kMaxSceneFileBytes) + " bytes";
      } else {
        why = view::CheckSceneFiles(*files);
      }
    }
    if (!why.empty()) {
      spdlog::error("instructor: station '{}': scene description refused: {}", station, why);
    }
    if (!Admit(station, "scene_description")) continue;
    std::lock_guard<std::mutex> lock(mutex_);
    if (!why.empty()) Reject("scene_description", why);
    StationView& v = ViewFor(station);
    Heard(v, MonotonicNowNs());
    if (why.empty()) {
      v.scene_files = std::move(files);
      v.scene_error.clear();
    } else {
      v.scene_error = why;
    }
  }
}

void Instructor::HandleOverlays() {
  msg::CueOverlay m;
  dds::SampleInfo si;
  OverlayMirror o;
  for (int taken = 0; TakeNext(dds_->overlay, &m, &si, taken);) {
    if (!si.valid_data || !FromItsStation(&si, m.station_id().c_str(), "cue_overlay")) continue;
    std::string why;
    if (!net::FromMsg(m, o.header, o.active_cues, o.overlay, &why)) {
      std::lock_guard<std::mutex> lock(mutex_);
      Reject("cue_overlay", why);
      continue;
    }
    if (!Admit(o.header.station_id, "cue_overlay")) continue;
    Record(static_cast<int>(record::TopicIndex::kCueOverlay), m, &si);
    const std::int64_t now = MonotonicNowNs();
    std::lock_guard<std::mutex> lock(mutex_);
    StationView& v = ViewFor(o.header.station_id);
    Heard(v, now);
    v.overlay.latest = o;
    v.overlay.received_ns = now;
    ++v.overlay.count;
  }
}

std::optional<StationView> Instructor::Station(const std::string& station_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = stations_.find(station_id);
  if (it == stations_.end()) return std::nullopt;
  return it->second;
}

std::vector<net::TaskEvent> Instructor::TakeEvents() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<net::TaskEvent> out;
  out.swap(new_events_);
  return out;
}

std::vector<net::Score> Instructor::TakeFinalScores() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<net::Score> out;
  out.swap(final_scores_);
  return out;
}

LatencySamples Instructor::TakeLatency() {
  std::lock_guard<std::mutex> lock(mutex_);
  LatencySamples out;
  std::swap(out, latency_);
  return out;
}

RejectedSamples Instructor::Rejected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rejected_;
}

std::vector<InputGap> Instructor::InputGaps() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return gaps_;
}

std::string FormatRejected(const RejectedSamples& rejected) {
  if (rejected.total == 0) return {};
  std::string out = "rejected " + std::to_string(rejected.total) + " received samples:";
  bool first = true;
  for (const auto& [topic, n] : rejected.by_topic) {
    out += first ? " " : ", ";
    out += topic;
    out += ' ';
    out += std::to_string(n);
    first = false;
  }
  return out + " (latest: " + rejected.last_reason + ")";
}

std::string FormatRejectedMetadata(const RejectedSamples& rejected) {
  std::string out;
  for (const auto& [topic, n] : rejected.by_topic) out += topic + " " + std::to_string(n) + "\n";
  return out;
}

std::string FormatInputGaps(const std::vector<InputGap>& gaps, std::int64_t from_realtime_ns) {
  std::string out;
  for (const auto& g : gaps) {
    if (g.receive_ns < from_realtime_ns) continue;
    out += g.station_id + " " + g.session_id + " " + std::to_string(g.first_missing_step) + " " +
           std::to_string(g.last_missing_step) + " " + std::to_string(g.receive_ns) + "\n";
  }
  return out;
}

std::string FormatStationTable(const std::vector<StationView>& stations, std::int64_t now_ns) {
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line,
                "%-12s %-18s %-22s %-20s %-6s %7s %5s %-28s %4s %-12s %6s %-6s %7s %13s %11s\n",
                "STATION", "TRAINEE", "SCENE", "MODULES", "STATE", "P99_ms", "OVR", "MODULE_STATE",
                "FLT", "CUES", "SCORE", "TASK", "AGE_ms", "INPUT_rx/lost", "INVALID_c/d");
  os << line;
  for (const StationView& v : stations) {
    std::string modules;
    for (const auto& m : v.info.modules) {
      if (!modules.empty()) modules += ',';
      modules += m;
    }
    std::string scene = v.info.scene;
    if (const auto slash = scene.rfind('/'); slash != std::string::npos)
      scene = scene.substr(slash + 1);
    double p99 = NAN, score = NAN, age = NAN;
    std::uint64_t overruns = 0;
    std::uint32_t contacts = 0;
    // The station's own count of the invalid samples it received: cues / device samples.
    std::string invalid = "-";
    std::string cues;  // active cue kinds, "" shown as "-"
    if (v.telemetry.latest) {
      p99 = v.telemetry.latest->period_p99_s * 1e3;
      overruns = v.telemetry.latest->overruns;
      invalid = std::to_string(v.telemetry.latest->cues_invalid) + "/" +
                std::to_string(v.telemetry.latest->device_samples_invalid);
    }
    // The latest mirrored module states, briefly: needle clearance, thread strain and grasp
    // force, tissue depth.
    std::string state;
    char part[64];
    if (v.needle.latest) {
      std::snprintf(part, sizeof part, "clr %.3fmm", v.needle.latest->clearance_m * 1e3);
      state += part;
    }
    if (v.thread.latest) {
      std::snprintf(part, sizeof part, "%sstr %.1f%% %.2fN", state.empty() ? "" : " ",
                    v.thread.latest->max_strain * 1e2, v.thread.latest->f_T_W.norm());
      state += part;
    }
    if (v.tissue.latest) {
      std::snprintf(part, sizeof part, "%sw %.2fmm", state.empty() ? "" : " ",
                    v.tissue.latest->max_displacement_m * 1e3);
      state += part;
    }
    if (v.tool.latest) {
      age = static_cast<double>(now_ns - v.tool.received_ns) * 1e-6;
      for (std::uint32_t k = 1; k < cues::kCueKindCount; ++k) {
        if ((v.tool.latest->active_cues >> k) & 1u) {
          if (!cues.empty()) cues += ',';
          cues += cues::CueKindName(cues::CueKind(k));
        }
      }
    }
    // The task: its progress, or how it ended; "-" for a scene without one (follow_path).
    std::string task = "-";
    if (v.score.latest) {
      score = v.score.latest->score;
      contacts = v.score.latest->contacts;
      const net::Score& sc = *v.score.latest;
      if (sc.outcome == 1) {
        task = "done";
      } else if (sc.outcome == 2) {
        task = "limit";
      } else if (sc.task != "follow_path" && !sc.task.empty()) {
        task = std::to_string(static_cast<int>(std::lround(100 * sc.progress))) + "%";
      }
    }
    char io[64] = "-";  // DeviceInput not taken (no recording, no --inputs)
    if (v.inputs_taken) {
      std::snprintf(io, sizeof io, "%llu/%llu", static_cast<unsigned long long>(v.inputs_received),
                    static_cast<unsigned long long>(v.inputs_lost));
    }
    std::snprintf(line, sizeof line,
                  "%-12.12s %-18.18s %-22.22s %-20.20s %-6s %7.3f %5llu %-28.28s %4u %-12.12s "
                  "%6.1f %-6.6s %7.1f %13s %11s\n",
                  v.info.header.station_id.c_str(), v.info.trainee.c_str(), scene.c_str(),
                  modules.c_str(), PresenceName(v.presence), p99,
                  static_cast<unsigned long long>(overruns), state.empty() ? "-" : state.c_str(),
                  contacts, cues.empty() ? "-" : cues.c_str(), score, task.c_str(), age, io,
                  invalid.c_str());
    os << line;
  }
  return os.str();
}

}  // namespace microdex::instructor
