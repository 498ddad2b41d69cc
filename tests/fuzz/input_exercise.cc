#include "tests/fuzz/input_exercise.h"

#include <cstring>
#include <exception>
#include <stdexcept>

#include "common/cues/cue_kind.h"
#include "common/net/convert.h"
#include "common/net/dds_context.h"
#include "common/net/overlay_convert.h"
#include "common/scene/scene.h"
#include "common/view/view_server.h"
#include "cue_commandPubSubTypes.h"
#include "cue_overlayPubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "instructor/console_message.h"
#include "instructor/console_session.h"
#include "needle_statePubSubTypes.h"
#include "scorePubSubTypes.h"
#include "station/page_device.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"
#include "tool_statePubSubTypes.h"

namespace microdex::fuzz {
namespace {

using eprosima::fastrtps::rtps::SerializedPayload_t;

// As a reader gets it: through the type support the apps register (net::DdsContext).
template <class PubSubType, class Msg>
bool Deserialize(const std::uint8_t* data, std::size_t size, Msg& msg) {
  net::CheckedPubSubType<PubSubType> type;
  SerializedPayload_t payload(static_cast<std::uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<std::uint32_t>(size);
  return type.deserialize(&payload, &msg);
}

template <class PubSubType, class Msg, class Plain>
SampleResult Check(const std::uint8_t* data, std::size_t size) {
  SampleResult r;
  Msg msg;
  r.deserialized = Deserialize<PubSubType>(data, size, msg);
  if (!r.deserialized) return r;
  Plain plain;
  std::string why;
  r.valid = net::FromMsg(msg, plain, &why);
  if (!r.valid && why.empty()) throw std::logic_error("FromMsg refused a sample without a reason");
  return r;
}

template <class PubSubType, class Msg>
std::vector<std::uint8_t> Serialize(Msg& msg, std::uint8_t type_index) {
  PubSubType type;
  const std::uint32_t size = type.getSerializedSizeProvider(&msg)();
  SerializedPayload_t payload(size);
  if (!type.serialize(&msg, &payload)) throw std::logic_error("serialize failed");
  std::vector<std::uint8_t> out{type_index};
  out.insert(out.end(), payload.data, payload.data + payload.length);
  return out;
}

net::Header SeedHeader() { return {"st-1", "st-1-1700000000000-1", 1234, 1700000000000000000}; }

}  // namespace

bool ExerciseSceneText(std::string_view text) {
  try {
    scene::ParseScene(std::string(text), "fuzz.yaml");
    return true;
  } catch (const std::exception&) {
    return false;  // scene::SceneError and what the loaders let through: caught by main
  }
}

SampleResult ExerciseSample(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return {};
  const std::uint8_t* p = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % kSampleTypes) {
    case 0:
      return Check<msg::StationInfoPubSubType, msg::StationInfo, net::StationInfo>(p, n);
    case 1:
      return Check<msg::DeviceInputPubSubType, msg::DeviceInput, net::DeviceInput>(p, n);
    case 2:
      return Check<msg::ToolStatePubSubType, msg::ToolState, net::ToolState>(p, n);
    case 3:
      return Check<msg::NeedleStatePubSubType, msg::NeedleState, net::NeedleState>(p, n);
    case 4:
      return Check<msg::ThreadStatePubSubType, msg::ThreadState, net::ThreadState>(p, n);
    case 5:
      return Check<msg::TissueStatePubSubType, msg::TissueState, net::TissueState>(p, n);
    case 6:
      return Check<msg::TelemetryPubSubType, msg::Telemetry, net::Telemetry>(p, n);
    case 7: {
      SampleResult r = Check<msg::CueCommandPubSubType, msg::CueCommand, net::CueCommand>(p, n);
      if (r.valid) {  // the station's own check before a cue reaches the haptic thread
        msg::CueCommand m;
        net::CueCommand c;
        Deserialize<msg::CueCommandPubSubType>(p, n, m);
        net::FromMsg(m, c);
        r.valid = cues::CheckCue(c.kind, c.param, c.off).empty();
      }
      return r;
    }
    case 8:
      return Check<msg::TaskEventPubSubType, msg::TaskEvent, net::TaskEvent>(p, n);
    case 9:
      return Check<msg::ScorePubSubType, msg::Score, net::Score>(p, n);
    default: {
      SampleResult r;
      msg::CueOverlay m;
      r.deserialized = Deserialize<msg::CueOverlayPubSubType>(p, n, m);
      if (!r.deserialized) return r;
      net::Header header;
      std::uint32_t active = 0;
      cues::CueOverlay overlay;
      r.valid = net::FromMsg(m, header, active, overlay);
      return r;
    }
  }
}

std::vector<std::pair<std::string, std::vector<std::uint8_t>>> ValidSamples() {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
  {
    net::StationInfo in;
    in.header = SeedHeader();
    in.trainee = "trainee 1";
    in.scene = "assets/scenes/needle_tube.yaml";
    in.modules = {"needle", "tremor"};
    in.build = "1.0";
    in.haptic_rate_hz = 1000;
    in.mirror_rate_hz = 60;
    in.skill = 0.5;
    in.device = "sim";
    msg::StationInfo m;
    net::ToMsg(in, m);
    out.emplace_back("station_info", Serialize<msg::StationInfoPubSubType>(m, 0));
  }
  {
    net::DeviceInput in;
    in.header = SeedHeader();
    in.p_WT = {1e-3, 2e-3, 3e-3};
    in.gripper = 0.5;
    msg::DeviceInput m;
    net::ToMsg(in, m);
    out.emplace_back("device_input", Serialize<msg::DeviceInputPubSubType>(m, 1));
  }
  {
    net::ToolState in;
    in.header = SeedHeader();
    in.active_cues = cues::CueBit(cues::CueKind::kWall);
    msg::ToolState m;
    net::ToMsg(in, m);
    out.emplace_back("tool_state", Serialize<msg::ToolStatePubSubType>(m, 2));
  }
  {
    net::NeedleState in;
    in.header = SeedHeader();
    in.clearance_m = 3e-4;
    msg::NeedleState m;
    net::ToMsg(in, m);
    out.emplace_back("needle_state", Serialize<msg::NeedleStatePubSubType>(m, 3));
  }
  {
    net::ThreadState in;
    in.header = SeedHeader();
    in.nodes = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1e-3, 0, 0)};
    in.knot = "overhand";
    msg::ThreadState m;
    net::ToMsg(in, m);
    out.emplace_back("thread_state", Serialize<msg::ThreadStatePubSubType>(m, 4));
  }
  {
    net::TissueState in;
    in.header = SeedHeader();
    in.nodes_x = 2;
    in.nodes_y = 2;
    in.length_x_m = in.length_y_m = 0.01;
    in.displacement_m = {0, 1e-4f, 2e-4f, 0};
    msg::TissueState m;
    net::ToMsg(in, m);
    out.emplace_back("tissue_state", Serialize<msg::TissueStatePubSubType>(m, 5));
  }
  {
    net::Telemetry in;
    in.header = SeedHeader();
    in.ticks = 100;
    in.period_mean_s = 1e-3;
    in.modules = {{"needle", 1e-5, 2e-5, 0, "", 0}};
    msg::Telemetry m;
    net::ToMsg(in, m);
    out.emplace_back("telemetry", Serialize<msg::TelemetryPubSubType>(m, 6));
  }
  {
    net::CueCommand in;
    in.header = SeedHeader();
    in.cue_id = 7;
    in.kind = cues::CueKind::kConvergentField;
    in.param = 300;
    in.issuer = "instructor";
    msg::CueCommand m;
    net::ToMsg(in, m);
    out.emplace_back("cue_command", Serialize<msg::CueCommandPubSubType>(m, 7));
  }
  {
    net::TaskEvent in;
    in.header = SeedHeader();
    in.kind = net::TaskEventKind::kCueApplied;
    in.cue_id = 7;
    in.text = "applied";
    msg::TaskEvent m;
    net::ToMsg(in, m);
    out.emplace_back("task_event", Serialize<msg::TaskEventPubSubType>(m, 8));
  }
  {
    net::Score in;
    in.header = SeedHeader();
    in.score = 80;
    msg::Score m;
    net::ToMsg(in, m);
    out.emplace_back("score", Serialize<msg::ScorePubSubType>(m, 9));
  }
  {
    cues::CueOverlay overlay;
    msg::CueOverlay m;
    net::ToMsg(SeedHeader(), 0, overlay, m);
    out.emplace_back("cue_overlay", Serialize<msg::CueOverlayPubSubType>(m, 10));
  }
  return out;
}

int ExerciseWsMessage(const std::string& text) {
  int accepted = 0;
  try {
    station::ParsePageInput(text);
    ++accepted;
  } catch (const std::invalid_argument&) {
  }
  try {
    instructor::ParseConsoleMessage(text);
    ++accepted;
  } catch (const std::invalid_argument&) {
  }
  try {
    instructor::ParseSessionMessage(text);
    ++accepted;
  } catch (const std::invalid_argument&) {
  }
  try {
    view::ParseCredit(text);
    ++accepted;
  } catch (const std::invalid_argument&) {
  }
  return accepted;
}

}  // namespace microdex::fuzz
