// The generated DDS types serialise to CDR and back without loss, and a truncated or hostile
// payload is rejected without a crash.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>

#include "cue_command.h"
#include "cue_commandPubSubTypes.h"
#include "device_input.h"
#include "device_inputPubSubTypes.h"
#include "needle_state.h"
#include "needle_statePubSubTypes.h"
#include "scene_description.h"
#include "scene_descriptionPubSubTypes.h"
#include "score.h"
#include "scorePubSubTypes.h"
#include "station_info.h"
#include "station_infoPubSubTypes.h"
#include "task_event.h"
#include "task_eventPubSubTypes.h"
#include "telemetry.h"
#include "telemetryPubSubTypes.h"
#include "thread_state.h"
#include "thread_statePubSubTypes.h"
#include "tissue_state.h"
#include "tissue_statePubSubTypes.h"
#include "tool_state.h"
#include "tool_statePubSubTypes.h"

namespace microdex::msg {
namespace {

using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

template <class T>
void FillHeader(T& m, const char* station = "station-3") {
  m.station_id(station);
  m.session_id("2026-11-21T10:00:00Z/3");
  m.step(123456789012ULL);
  m.stamp_ns(-42);
}

StationInfo MakeStationInfo() {
  StationInfo info;
  FillHeader(info);
  info.trainee("Dr. Ünal");
  info.scene("assets/scenes/needle_tube.yaml");
  info.modules().resize(2);
  info.modules()[0].name("needle");
  info.modules()[1].name("tremor");
  info.build("0.1.0");
  info.haptic_rate_hz(1000.0);
  info.mirror_rate_hz(60.0);
  info.skill(0.25);
  info.device("sim");
  info.scene_hash(0x0123456789abcdefULL);
  return info;
}

SceneDescription MakeSceneDescription() {
  SceneDescription m;
  FillHeader(m);
  m.scene_path("scenes/needle_tube.yaml");
  m.hash(0xfedcba9876543210ULL);
  m.files().resize(2);
  m.files()[0].path("scenes/needle_tube.yaml");
  const std::string yaml = "name: needle-in-tube\nmodules: [needle]\n";
  m.files()[0].bytes().assign(yaml.begin(), yaml.end());
  m.files()[1].path("meshes/vessel.glb");
  m.files()[1].bytes().assign(300, 0x5a);
  return m;
}

DeviceInput MakeDeviceInput() {
  DeviceInput m;
  FillHeader(m);
  m.p_WT({1e-3, -2e-3, 3.5e-3});
  m.q_WT({0.5, 0.5, -0.5, 0.5});
  m.gripper(0.75);
  m.buttons(5);
  return m;
}

ToolState MakeToolState() {
  ToolState m;
  FillHeader(m);
  m.p_WT({1e-3, 2e-3, 3e-3});
  m.q_WT({1, 0, 0, 0});
  m.f_T_W({0.01, -0.02, 0.03});
  m.tremor_rms_m(3e-5);
  m.active_cues(0b1010);
  return m;
}

NeedleState MakeNeedleState() {
  NeedleState m;
  FillHeader(m);
  m.p_WN({0, 0, 1e-3});
  m.q_WN({0, 1, 0, 0});
  m.clearance_m(-1.5e-5);
  m.contact(1);
  m.s_rad(0.7);
  m.p_WD({4e-3, 1e-3, 0});
  m.p_WB({4.1e-3, 1e-3, 0});
  m.status(microdex::msg::CLEARANCE_OK);
  return m;
}

ThreadState MakeThreadState() {
  ThreadState m;
  FillHeader(m);
  for (int i = 0; i < 100; ++i) {
    ThreadNode n;
    n.x(i * 1e-4);
    n.y(-i * 2e-4);
    n.z(i * i * 1e-6);
    m.nodes().push_back(n);
  }
  m.knot("square");
  m.max_strain(0.01);
  m.grasped_node(99);
  m.f_T_W({0.1, 0.2, -0.3});
  return m;
}

TissueState MakeTissueState() {
  TissueState m;
  FillHeader(m);
  m.p_WS({-0.01, -0.01, 0});
  m.q_WS({1, 0, 0, 0});
  m.length_x_m(0.02);
  m.length_y_m(0.02);
  m.nodes_x(60);
  m.nodes_y(50);
  m.mesh_revision(7);
  m.unknowns(829);
  m.max_displacement_m(1e-3);
  m.status(microdex::msg::TISSUE_OK);
  for (int i = 0; i < 3000; ++i) m.displacement_m().push_back(static_cast<float>(i) * 1e-7f);
  return m;
}

Telemetry MakeTelemetry() {
  Telemetry m;
  FillHeader(m);
  m.window_s(0.1);
  m.ticks(100);
  m.period_mean_s(1.0e-3);
  m.period_p99_s(1.05e-3);
  m.period_max_s(2.5e-3);
  m.overruns(2);
  m.ring_dropped(1);
  m.realtime(1);
  ModuleTelemetry mt;
  mt.name("needle");
  mt.step_time_mean_s(2e-6);
  mt.step_time_max_s(9e-6);
  mt.error_estimate(1e-9);
  mt.error_kind("sp_vs_exact_m");
  mt.warnings(0);
  m.modules().push_back(mt);
  mt.name("tremor");
  m.modules().push_back(mt);
  return m;
}

CueCommand MakeCueCommand() {
  CueCommand m;
  FillHeader(m, "all");
  m.cue_id(99);
  m.kind(CUE_DIVERGENT_FIELD);
  m.param(150.0);
  m.issuer("instructor-1");
  return m;
}

TaskEvent MakeTaskEvent() {
  TaskEvent m;
  FillHeader(m);
  m.kind(EVENT_CUE_APPLIED);
  m.cue_id(99);
  m.value(0.5);
  m.text("divergent 150 N/m");
  return m;
}

Score MakeScore() {
  Score m;
  FillHeader(m);
  m.is_final(1);
  m.duration_s(30);
  m.time_in_contact_s(1.25);
  m.contacts(4);
  m.mean_clearance_m(2e-4);
  m.min_clearance_m(-3e-5);
  m.path_length_m(0.05);
  m.ideal_path_length_m(0.04);
  m.tremor_rms_m(2e-5);
  m.score(71.5);
  return m;
}

template <class Msg, class PubSub>
struct Case {
  using MsgType = Msg;
  using PubSubType = PubSub;
};

template <class C>
class IdlRoundTrip : public ::testing::Test {};

using Cases = ::testing::Types<
    Case<StationInfo, StationInfoPubSubType>, Case<DeviceInput, DeviceInputPubSubType>,
    Case<ToolState, ToolStatePubSubType>, Case<NeedleState, NeedleStatePubSubType>,
    Case<ThreadState, ThreadStatePubSubType>, Case<TissueState, TissueStatePubSubType>,
    Case<Telemetry, TelemetryPubSubType>, Case<CueCommand, CueCommandPubSubType>,
    Case<TaskEvent, TaskEventPubSubType>, Case<Score, ScorePubSubType>,
    Case<SceneDescription, SceneDescriptionPubSubType>>;
TYPED_TEST_SUITE(IdlRoundTrip, Cases);

StationInfo Make(StationInfo*) { return MakeStationInfo(); }
DeviceInput Make(DeviceInput*) { return MakeDeviceInput(); }
ToolState Make(ToolState*) { return MakeToolState(); }
NeedleState Make(NeedleState*) { return MakeNeedleState(); }
ThreadState Make(ThreadState*) { return MakeThreadState(); }
TissueState Make(TissueState*) { return MakeTissueState(); }
Telemetry Make(Telemetry*) { return MakeTelemetry(); }
CueCommand Make(CueCommand*) { return MakeCueCommand(); }
TaskEvent Make(TaskEvent*) { return MakeTaskEvent(); }
Score Make(Score*) { return MakeScore(); }
SceneDescription Make(SceneDescription*) { return MakeSceneDescription(); }

template <class C>
typename C::MsgType MakeSample() {
  return Make(static_cast<typename C::MsgType*>(nullptr));
}

TYPED_TEST(IdlRoundTrip, SurvivesCdr) {
  typename TypeParam::PubSubType type;
  auto in = MakeSample<TypeParam>();
  SerializedPayload_t payload(type.getSerializedSizeProvider(&in)());
  ASSERT_TRUE(type.serialize(&in, &payload));
  EXPECT_GT(payload.length, 0u);
  typename TypeParam::MsgType out;
  ASSERT_TRUE(type.deserialize(&payload, &out));
  EXPECT_TRUE(out == in);
  EXPECT_EQ(out.station_id(), in.station_id());
  EXPECT_EQ(out.session_id(), in.session_id());
  EXPECT_EQ(out.step(), 123456789012ULL);
  EXPECT_EQ(out.stamp_ns(), -42);
}

TYPED_TEST(IdlRoundTrip, KeyIsTheStationId) {
  typename TypeParam::PubSubType type;
  EXPECT_TRUE(type.m_isGetKeyDefined);
  auto a = MakeSample<TypeParam>();
  auto b = MakeSample<TypeParam>();
  b.step(7);  // same station, another sample
  b.session_id("other session");
  InstanceHandle_t ha, hb;
  ASSERT_TRUE(type.getKey(&a, &ha));
  ASSERT_TRUE(type.getKey(&b, &hb));
  EXPECT_EQ(ha, hb);
  b.station_id("station-4");
  ASSERT_TRUE(type.getKey(&b, &hb));
  EXPECT_NE(ha, hb);
}

TYPED_TEST(IdlRoundTrip, TruncatedPayloadIsRejected) {
  typename TypeParam::PubSubType type;
  auto in = MakeSample<TypeParam>();
  SerializedPayload_t payload(type.getSerializedSizeProvider(&in)());
  ASSERT_TRUE(type.serialize(&in, &payload));
  const uint32_t full = payload.length;
  // Every cut that removes at least the last 8 bytes (a whole double or length field) must
  // be refused; cuts into trailing alignment padding may legitimately succeed.
  for (uint32_t cut = 4; cut + 8 <= full; cut += 3) {
    payload.length = cut;
    typename TypeParam::MsgType out;
    EXPECT_FALSE(type.deserialize(&payload, &out)) << "accepted a payload cut at " << cut;
  }
}

TYPED_TEST(IdlRoundTrip, HostileLengthFieldIsRejected) {
  // Overwrite each aligned 4-byte word in turn with 0xFFFFFFF0: wherever a string or sequence
  // length sits, the deserializer sees a length far beyond the payload and must refuse it
  // without allocating gigabytes or crashing; elsewhere it is just a wrong number.
  typename TypeParam::PubSubType type;
  auto in = MakeSample<TypeParam>();
  SerializedPayload_t payload(type.getSerializedSizeProvider(&in)());
  ASSERT_TRUE(type.serialize(&in, &payload));
  const uint32_t full = payload.length;
  int refused = 0;
  for (uint32_t at = 4; at + 4 <= full && at < 4000; at += 4) {
    SerializedPayload_t hostile(full);
    std::memcpy(hostile.data, payload.data, full);
    hostile.length = full;
    const uint32_t bad = 0xFFFFFFF0u;
    std::memcpy(hostile.data + at, &bad, 4);
    typename TypeParam::MsgType out;
    if (!type.deserialize(&hostile, &out)) ++refused;
  }
  // The station_id length at offset 4 is always one of the words overwritten.
  EXPECT_GE(refused, 1);
}

}  // namespace
}  // namespace microdex::msg
