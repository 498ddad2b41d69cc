#include "tests/fuzz/record_reader_exercise.h"

#include <fastdds/rtps/common/SerializedPayload.h>

#include "common/record/recorded_topics.h"
#include "common/record/session_reader.h"
#include "common/record/session_writer.h"
#include "cue_commandPubSubTypes.h"
#include "cue_overlayPubSubTypes.h"
#include "device_forcePubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "instructor/recorded_sample.h"
#include "needle_statePubSubTypes.h"
#include "scorePubSubTypes.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"
#include "tool_statePubSubTypes.h"

namespace microdex::fuzz {
namespace {

using record::TopicIndex;

template <class PubSubType, class Msg>
bool Decode(std::span<const std::uint8_t> cdr) {
  Msg m;
  return instructor::DecodeSample<PubSubType>(cdr, m);
}

bool DecodeAny(int topic, std::span<const std::uint8_t> cdr) {
  switch (static_cast<TopicIndex>(topic)) {
    case TopicIndex::kStationInfo:
      return Decode<msg::StationInfoPubSubType, msg::StationInfo>(cdr);
    case TopicIndex::kDeviceInput:
      return Decode<msg::DeviceInputPubSubType, msg::DeviceInput>(cdr);
    case TopicIndex::kToolState:
      return Decode<msg::ToolStatePubSubType, msg::ToolState>(cdr);
    case TopicIndex::kNeedleState:
      return Decode<msg::NeedleStatePubSubType, msg::NeedleState>(cdr);
    case TopicIndex::kThreadState:
      return Decode<msg::ThreadStatePubSubType, msg::ThreadState>(cdr);
    case TopicIndex::kTissueState:
      return Decode<msg::TissueStatePubSubType, msg::TissueState>(cdr);
    case TopicIndex::kTelemetry:
      return Decode<msg::TelemetryPubSubType, msg::Telemetry>(cdr);
    case TopicIndex::kCueCommand:
      return Decode<msg::CueCommandPubSubType, msg::CueCommand>(cdr);
    case TopicIndex::kTaskEvent:
      return Decode<msg::TaskEventPubSubType, msg::TaskEvent>(cdr);
    case TopicIndex::kScore:
      return Decode<msg::ScorePubSubType, msg::Score>(cdr);
    case TopicIndex::kCueOverlay:
      return Decode<msg::CueOverlayPubSubType, msg::CueOverlay>(cdr);
    case TopicIndex::kDeviceForce:
      return Decode<msg::DeviceForcePubSubType, msg::DeviceForce>(cdr);
  }
  return false;
}

template <class PubSubType, class Msg>
record::RecordedMessage Serialize(TopicIndex topic, Msg& m, std::uint64_t step) {
  PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&m)());
  type.serialize(&m, &payload);
  record::RecordedMessage r;
  r.topic = static_cast<int>(topic);
  r.station = m.station_id();
  r.session = m.session_id();
  r.receive_ns = 1'795'000'000'000'000'000 + static_cast<std::int64_t>(step) * 1'000'000;
  r.source_ns = r.receive_ns - 150'000;
  r.sequence = static_cast<std::int64_t>(step) + 1;
  r.step = step;
  r.cdr.assign(payload.data, payload.data + payload.length);
  return r;
}

template <class Msg>
void Header(Msg& m, std::uint64_t step) {
  m.station_id("seed-1");
  m.session_id("seed-1-1795000000000-1");
  m.step(step);
  m.stamp_ns(1'795'000'000'000'000'000 + static_cast<std::int64_t>(step) * 1'000'000);
}

}  // namespace

ExerciseResult ExerciseReader(const std::string& path) {
  ExerciseResult r;
  try {
    record::SessionReader reader(path);
    r.opened = true;
    reader.ForEach({}, [&](const record::MessageView& m) {
      ++r.messages;
      r.decoded += DecodeAny(m.topic, m.cdr) ? 1 : 0;
      return true;
    });
    reader.Stations();
    reader.TimeRange();
    r.problems = reader.problems().size();
    if (r.problems > 0) r.first_problem = reader.problems()[0];
  } catch (const record::RecordError& e) {
    r.error = e.what();
  }
  return r;
}

void WriteSeedRecording(const std::string& path) {
  record::SessionWriter w(path, {{"issuer", "seed"}});
  std::vector<record::RecordedMessage> batch;
  msg::StationInfo info;
  Header(info, 0);
  info.scene("assets/scenes/needle_tube.yaml");
  info.modules().resize(2);
  info.modules()[0].name("needle");
  info.modules()[1].name("tremor");
  info.seed(7);
  batch.push_back(Serialize<msg::StationInfoPubSubType>(TopicIndex::kStationInfo, info, 0));
  for (std::uint64_t s = 0; s < 3; ++s) {
    msg::DeviceInput in;
    Header(in, s);
    in.p_WT({0.001 * static_cast<double>(s), 0.002, 0.003});
    in.q_WT({1, 0, 0, 0});
    in.state_hash(0x1234567890abcdefULL + s);
    batch.push_back(Serialize<msg::DeviceInputPubSubType>(TopicIndex::kDeviceInput, in, s));
  }
  msg::ToolState tool;
  Header(tool, 2);
  batch.push_back(Serialize<msg::ToolStatePubSubType>(TopicIndex::kToolState, tool, 2));
  msg::NeedleState needle;
  Header(needle, 2);
  batch.push_back(Serialize<msg::NeedleStatePubSubType>(TopicIndex::kNeedleState, needle, 2));
  msg::ThreadState thread;
  Header(thread, 2);
  thread.nodes().resize(4);
  thread.knot("none");
  batch.push_back(Serialize<msg::ThreadStatePubSubType>(TopicIndex::kThreadState, thread, 2));
  msg::TissueState tissue;
  Header(tissue, 2);
  tissue.nodes_x(3);
  tissue.nodes_y(3);
  tissue.displacement_m().assign(9, -1e-4F);
  batch.push_back(Serialize<msg::TissueStatePubSubType>(TopicIndex::kTissueState, tissue, 2));
  msg::Telemetry tel;
  Header(tel, 2);
  tel.modules().resize(1);
  tel.modules()[0].name("needle");
  tel.has_state_hash(1);
  batch.push_back(Serialize<msg::TelemetryPubSubType>(TopicIndex::kTelemetry, tel, 2));
  msg::CueCommand cue;
  Header(cue, 0);
  cue.cue_id(1);
  cue.kind(msg::CUE_CONVERGENT_FIELD);
  cue.param(150);
  cue.issuer("seed");
  batch.push_back(Serialize<msg::CueCommandPubSubType>(TopicIndex::kCueCommand, cue, 0));
  msg::TaskEvent ev;
  Header(ev, 1);
  ev.kind(msg::EVENT_CUE_APPLIED);
  ev.cue_id(1);
  ev.value(150);
  ev.text("convergent");
  batch.push_back(Serialize<msg::TaskEventPubSubType>(TopicIndex::kTaskEvent, ev, 1));
  msg::Score score;
  Header(score, 2);
  score.terms().resize(1);
  score.terms()[0].metric("deviation");
  batch.push_back(Serialize<msg::ScorePubSubType>(TopicIndex::kScore, score, 2));
  msg::CueOverlay overlay;
  Header(overlay, 2);
  overlay.polylines().resize(1);
  overlay.polylines()[0].p_W({0, 0, 0.002, 0.001, 0, 0.002});
  batch.push_back(Serialize<msg::CueOverlayPubSubType>(TopicIndex::kCueOverlay, overlay, 2));
  msg::DeviceForce force;
  Header(force, 2);
  force.f_D({0.1, -0.2, 0.05});
  batch.push_back(Serialize<msg::DeviceForcePubSubType>(TopicIndex::kDeviceForce, force, 2));
  w.Write(batch);
}

}  // namespace microdex::fuzz
