#include "instructor/instructor.h"

#include <spdlog/spdlog.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/LivelinessChangedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>

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
  if (!options_.record_file.empty()) {
    recorder_ = std::make_unique<record::Recorder>(
        options_.record_file,
        std::map<std::string, std::string>{{"recorder_session", session_id_},
                                           {"issuer", options_.issuer},
                                           {"dds_domain", std::to_string(options_.dds.domain_id)},
                                           {"dds_partition", options_.dds.partition}},
        options_.recorder);
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
  d.context = std::make_unique<net::DdsContext>(options_.dds);
  d.info = d.context->CreateReader<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  // Recording: readers that keep every sample until it is taken (net::RecordingReaderSpec).
  const auto spec = [&](const net::TopicSpec& s) {
    return recorder_ ? net::RecordingReaderSpec(s) : s;
  };
  d.input = d.context->CreateReader<msg::DeviceInputPubSubType>(spec(net::kDeviceInputTopic));
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
  if (recorder_) {
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
  }
  return it->second;
}

void Instructor::Run() {
  dds::ConditionSeq active;
  while (!stop_.load()) {
    dds_->waitset.wait(active, eprosima::fastrtps::Duration_t(0, 200'000'000));
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
    RecordOnly<msg::DeviceForce>(dds_->force, record::TopicIndex::kDeviceForce);
    CheckSilence();
  }
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
  while (dds_->info->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    net::StationInfo info;
    if (si.valid_data) {
      std::string why;
      if (!net::FromMsg(m, info, &why)) {
        std::lock_guard<std::mutex> lock(mutex_);
        Reject("station_info", why);
        continue;
      }
      if (!Admit(info.header.station_id, "station_info")) continue;
      Record(static_cast<int>(record::TopicIndex::kStationInfo), m, &si);
    }
    const std::int64_t now = MonotonicNowNs();
    std::lock_guard<std::mutex> lock(mutex_);
    if (si.valid_data) {
      dds_->instance_to_station[HandleKey(si.instance_handle)] = info.header.station_id;
      writer_to_station_[HandleKey(si.publication_handle)] = info.header.station_id;
      dds_->current_info_writer[info.header.station_id] = HandleKey(si.publication_handle);
      StationView& v = ViewFor(info.header.station_id);
      const bool known = v.info.header.session_id.size() > 0;
      if (known && v.presence != Presence::kAlive) ++v.comebacks;
      if (v.presence != Presence::kAlive || !known) v.presence_changed_ns = now;
      v.presence = Presence::kAlive;
      v.last_heard_ns = now;
      v.info = std::move(info);
      continue;
    }
    auto it = dds_->instance_to_station.find(HandleKey(si.instance_handle));
    if (it == dds_->instance_to_station.end()) continue;
    if (si.instance_state == dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE &&
        dds_->current_info_writer[it->second] != HandleKey(si.publication_handle)) {
      continue;  // an earlier run's departure, arriving after the current run's StationInfo
    }
    StationView& v = ViewFor(it->second);
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
  if (!recorder_) return;
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
  recorder_->Push(std::move(r));
}

template <class Msg, class Plain>
void Instructor::TakeAll(void* reader_ptr, Mirror<Plain> StationView::*mirror, const char* topic) {
  auto* reader = static_cast<dds::DataReader*>(reader_ptr);
  Msg m;
  dds::SampleInfo si;
  while (reader->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    if (!si.valid_data) continue;
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
void Instructor::RecordOnly(void* reader_ptr, record::TopicIndex topic) {
  auto* reader = static_cast<dds::DataReader*>(reader_ptr);
  if (reader == nullptr) return;
  Msg m;
  dds::SampleInfo si;
  while (reader->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    if (si.valid_data) Record(static_cast<int>(topic), m, &si);
  }
}

void Instructor::HandleInputs() {
  msg::DeviceInput m;
  dds::SampleInfo si;
  net::DeviceInput p;
  while (dds_->input->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    if (!si.valid_data) continue;
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
      if (recorder_) recorder_->SetMetadata("input_gaps", FormatInputGaps(gaps_));
    }
    v.last_input_step = p.header.step;
  }
}

void Instructor::HandleEvents() {
  msg::TaskEvent m;
  dds::SampleInfo si;
  while (dds_->events->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    if (!si.valid_data) continue;
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

std::optional<record::RecorderStats> Instructor::RecorderStats() const {
  if (!recorder_) return std::nullopt;
  return recorder_->stats();
}

void Instructor::FlushRecording() {
  if (recorder_) recorder_->Flush();
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
  while (dds_->scene->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    if (!si.valid_data) continue;
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
  while (dds_->overlay->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
    if (!si.valid_data) continue;
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

std::string FormatInputGaps(const std::vector<InputGap>& gaps) {
  std::string out;
  for (const auto& g : gaps) {
    out += g.station_id + " " + g.session_id + " " + std::to_string(g.first_missing_step) + " " +
           std::to_string(g.last_missing_step) + " " + std::to_string(g.receive_ns) + "\n";
  }
  return out;
}

std::string FormatStationTable(const std::vector<StationView>& stations, std::int64_t now_ns) {
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line,
                "%-12s %-18s %-22s %-20s %-6s %7s %5s %-28s %4s %-12s %6s %-6s %7s %13s\n",
                "STATION", "TRAINEE", "SCENE", "MODULES", "STATE", "P99_ms", "OVR", "MODULE_STATE",
                "FLT", "CUES", "SCORE", "TASK", "AGE_ms", "INPUT_rx/lost");
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
    std::string cues;  // active cue kinds, "" shown as "-"
    if (v.telemetry.latest) {
      p99 = v.telemetry.latest->period_p99_s * 1e3;
      overruns = v.telemetry.latest->overruns;
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
    char io[64];
    std::snprintf(io, sizeof io, "%llu/%llu", static_cast<unsigned long long>(v.inputs_received),
                  static_cast<unsigned long long>(v.inputs_lost));
    std::snprintf(line, sizeof line,
                  "%-12.12s %-18.18s %-22.22s %-20.20s %-6s %7.3f %5llu %-28.28s %4u %-12.12s "
                  "%6.1f %-6.6s %7.1f %13s\n",
                  v.info.header.station_id.c_str(), v.info.trainee.c_str(), scene.c_str(),
                  modules.c_str(), PresenceName(v.presence), p99,
                  static_cast<unsigned long long>(overruns), state.empty() ? "-" : state.c_str(),
                  contacts, cues.empty() ? "-" : cues.c_str(), score, task.c_str(), age, io);
    os << line;
  }
  return os.str();
}

}  // namespace microdex::instructor
