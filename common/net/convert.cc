#include "common/net/convert.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>

#include "common/base/check.h"

namespace microdex::net {
namespace {

constexpr std::size_t kMaxTraineeLength = 128;
constexpr std::size_t kMaxSceneLength = 256;
constexpr std::size_t kMaxTextLength = 128;

template <std::size_t N>
std::string S(const eprosima::fastrtps::fixed_string<N>& s) {
  return std::string(s.c_str());
}

// Collects the first reason a received sample is rejected.
class Checker {
 public:
  explicit Checker(std::string* why) : why_(why) {}
  bool ok() const { return ok_; }
  void Fail(const std::string& reason) {
    if (ok_ && why_ != nullptr) *why_ = reason;
    ok_ = false;
  }
  // The generated bounded strings (fixed_string<N>) already truncate at N on receipt; this
  // guards the plain side and any future unbounded field.
  void String(std::string_view s, std::size_t max, const char* field) {
    if (s.size() > max) Fail(std::string(field) + ": longer than " + std::to_string(max));
  }
  void Finite(double v, const char* field) {
    if (!std::isfinite(v)) Fail(std::string(field) + ": not finite");
  }
  template <std::size_t N>
  void Finite(const std::array<double, N>& v, const char* field) {
    for (double x : v) Finite(x, field);
  }
  void Unit(const std::array<double, 4>& q, const char* field) {
    Finite(q, field);
    const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if (ok_ && std::abs(n2 - 1.0) > 1e-6) Fail(std::string(field) + ": not a unit quaternion");
  }
  // Finite values outside a plausible range (a corrupt or hostile sample).
  void Range(double v, double lo, double hi, const char* field) {
    if (std::isfinite(v) && !(v >= lo && v <= hi)) {
      Fail(std::string(field) + ": outside " + Num(lo) + " .. " + Num(hi));
    }
  }
  template <std::size_t N>
  void Range(const std::array<double, N>& v, double max_abs, const char* field) {
    for (double x : v) Range(x, -max_abs, max_abs, field);
  }
  void Flag(std::uint8_t v, const char* field) {
    if (v > 1) Fail(std::string(field) + ": flag other than 0 or 1");
  }

 private:
  static std::string Num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
  }
  std::string* why_;
  bool ok_ = true;
};

// Every position of the trainer lies within a few decimetres of its origin; 10 m is far beyond
// any scene and any device workspace.
constexpr double kMaxAbsPosition_m = 10.0;

template <class Msg>
void HeaderToMsg(const Header& in, Msg& out) {
  MICRODEX_CHECK(in.station_id.size() <= kMaxIdLength && in.session_id.size() <= kMaxIdLength);
  out.station_id(in.station_id);
  out.session_id(in.session_id);
  out.step(in.step);
  out.stamp_ns(in.stamp_ns);
}

template <class Msg>
void HeaderFromMsg(const Msg& in, Header& out, Checker& c) {
  c.String(S(in.station_id()), kMaxIdLength, "station_id");
  c.String(S(in.session_id()), kMaxIdLength, "session_id");
  if (S(in.station_id()).empty()) c.Fail("station_id: empty");
  // Ids are shown in tables and pages and used as file and map keys: printable ASCII only.
  for (const char ch : S(in.station_id())) {
    if (ch <= ' ' || ch > '~') {
      c.Fail("station_id: a character other than printable ASCII");
      break;
    }
  }
  out.station_id = S(in.station_id());
  out.session_id = S(in.session_id());
  out.step = in.step();
  out.stamp_ns = in.stamp_ns();
}

std::array<double, 3> V(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d V(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
std::array<double, 4> Q(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }
Eigen::Quaterniond Q(const std::array<double, 4>& a) { return {a[0], a[1], a[2], a[3]}; }

void CheckModuleName(const std::string& s) { MICRODEX_CHECK(s.size() <= kMaxModuleNameLength); }

}  // namespace

namespace {

// Cue kinds cross the IDL by name: each enumerator maps to its namesake, never by number.
msg::CueKind CueKindToMsg(cues::CueKind kind) {
  switch (kind) {
    case cues::CueKind::kClear:
      return msg::CUE_CLEAR;
    case cues::CueKind::kConvergentField:
      return msg::CUE_CONVERGENT_FIELD;
    case cues::CueKind::kDivergentField:
      return msg::CUE_DIVERGENT_FIELD;
    case cues::CueKind::kAmplifiedTremor:
      return msg::CUE_AMPLIFIED_TREMOR;
    case cues::CueKind::kVisualPath:
      return msg::CUE_VISUAL_PATH;
    case cues::CueKind::kVisualLimits:
      return msg::CUE_VISUAL_LIMITS;
    case cues::CueKind::kVisualDeviation:
      return msg::CUE_VISUAL_DEVIATION;
    case cues::CueKind::kVisualClearance:
      return msg::CUE_VISUAL_CLEARANCE;
    case cues::CueKind::kAudioClick:
      return msg::CUE_AUDIO_CLICK;
    case cues::CueKind::kAudioError:
      return msg::CUE_AUDIO_ERROR;
    case cues::CueKind::kAudioProximity:
      return msg::CUE_AUDIO_PROXIMITY;
    case cues::CueKind::kAudioGeiger:
      return msg::CUE_AUDIO_GEIGER;
    case cues::CueKind::kWall:
      return msg::CUE_WALL;
    case cues::CueKind::kPredictive:
      return msg::CUE_PREDICTIVE;
  }
  MICRODEX_CHECK(false);
  return msg::CUE_CLEAR;
}

bool CueKindFromMsg(msg::CueKind in, cues::CueKind* kind) {
  switch (in) {
    case msg::CUE_CLEAR:
      *kind = cues::CueKind::kClear;
      return true;
    case msg::CUE_CONVERGENT_FIELD:
      *kind = cues::CueKind::kConvergentField;
      return true;
    case msg::CUE_DIVERGENT_FIELD:
      *kind = cues::CueKind::kDivergentField;
      return true;
    case msg::CUE_AMPLIFIED_TREMOR:
      *kind = cues::CueKind::kAmplifiedTremor;
      return true;
    case msg::CUE_VISUAL_PATH:
      *kind = cues::CueKind::kVisualPath;
      return true;
    case msg::CUE_VISUAL_LIMITS:
      *kind = cues::CueKind::kVisualLimits;
      return true;
    case msg::CUE_VISUAL_DEVIATION:
      *kind = cues::CueKind::kVisualDeviation;
      return true;
    case msg::CUE_VISUAL_CLEARANCE:
      *kind = cues::CueKind::kVisualClearance;
      return true;
    case msg::CUE_AUDIO_CLICK:
      *kind = cues::CueKind::kAudioClick;
      return true;
    case msg::CUE_AUDIO_ERROR:
      *kind = cues::CueKind::kAudioError;
      return true;
    case msg::CUE_AUDIO_PROXIMITY:
      *kind = cues::CueKind::kAudioProximity;
      return true;
    case msg::CUE_AUDIO_GEIGER:
      *kind = cues::CueKind::kAudioGeiger;
      return true;
    case msg::CUE_WALL:
      *kind = cues::CueKind::kWall;
      return true;
    case msg::CUE_PREDICTIVE:
      *kind = cues::CueKind::kPredictive;
      return true;
  }
  return false;
}

// Task events likewise.
msg::TaskEventKind TaskEventKindToMsg(TaskEventKind kind) {
  switch (kind) {
    case TaskEventKind::kTaskStart:
      return msg::EVENT_TASK_START;
    case TaskEventKind::kTaskEnd:
      return msg::EVENT_TASK_END;
    case TaskEventKind::kCueApplied:
      return msg::EVENT_CUE_APPLIED;
    case TaskEventKind::kCueRejected:
      return msg::EVENT_CUE_REJECTED;
    case TaskEventKind::kContactBegin:
      return msg::EVENT_CONTACT_BEGIN;
    case TaskEventKind::kContactEnd:
      return msg::EVENT_CONTACT_END;
    case TaskEventKind::kDeviceFault:
      return msg::EVENT_DEVICE_FAULT;
    case TaskEventKind::kDeviceOk:
      return msg::EVENT_DEVICE_OK;
  }
  MICRODEX_CHECK(false);
  return msg::EVENT_TASK_START;
}

bool TaskEventKindFromMsg(msg::TaskEventKind in, TaskEventKind* kind) {
  switch (in) {
    case msg::EVENT_TASK_START:
      *kind = TaskEventKind::kTaskStart;
      return true;
    case msg::EVENT_TASK_END:
      *kind = TaskEventKind::kTaskEnd;
      return true;
    case msg::EVENT_CUE_APPLIED:
      *kind = TaskEventKind::kCueApplied;
      return true;
    case msg::EVENT_CUE_REJECTED:
      *kind = TaskEventKind::kCueRejected;
      return true;
    case msg::EVENT_CONTACT_BEGIN:
      *kind = TaskEventKind::kContactBegin;
      return true;
    case msg::EVENT_CONTACT_END:
      *kind = TaskEventKind::kContactEnd;
      return true;
    case msg::EVENT_DEVICE_FAULT:
      *kind = TaskEventKind::kDeviceFault;
      return true;
    case msg::EVENT_DEVICE_OK:
      *kind = TaskEventKind::kDeviceOk;
      return true;
  }
  return false;
}

}  // namespace

const char* TaskEventKindName(TaskEventKind kind) {
  switch (kind) {
    case TaskEventKind::kTaskStart:
      return "task-start";
    case TaskEventKind::kTaskEnd:
      return "task-end";
    case TaskEventKind::kCueApplied:
      return "cue-applied";
    case TaskEventKind::kCueRejected:
      return "cue-rejected";
    case TaskEventKind::kContactBegin:
      return "contact-begin";
    case TaskEventKind::kContactEnd:
      return "contact-end";
    case TaskEventKind::kDeviceFault:
      return "device-fault";
    case TaskEventKind::kDeviceOk:
      return "device-ok";
  }
  return "unknown";
}

// ---- StationInfo ----
void ToMsg(const StationInfo& in, msg::StationInfo& out) {
  HeaderToMsg(in.header, out);
  MICRODEX_CHECK(in.trainee.size() <= kMaxTraineeLength && in.scene.size() <= kMaxSceneLength);
  MICRODEX_CHECK(in.modules.size() <= kMaxModules && in.build.size() <= kMaxIdLength);
  MICRODEX_CHECK(in.device.size() <= kMaxModuleNameLength);
  for (const auto& m : in.modules) CheckModuleName(m);
  out.trainee(in.trainee);
  out.scene(in.scene);
  out.modules().resize(in.modules.size());
  for (std::size_t i = 0; i < in.modules.size(); ++i) out.modules()[i].name(in.modules[i]);
  out.build(in.build);
  out.haptic_rate_hz(in.haptic_rate_hz);
  out.mirror_rate_hz(in.mirror_rate_hz);
  out.skill(in.skill);
  out.device(in.device);
  out.seed(in.seed);
  out.scene_hash(in.scene_hash);
}

bool FromMsg(const msg::StationInfo& in, StationInfo& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  c.String(S(in.trainee()), kMaxTraineeLength, "trainee");
  c.String(S(in.scene()), kMaxSceneLength, "scene");
  c.String(S(in.build()), kMaxIdLength, "build");
  c.String(S(in.device()), kMaxModuleNameLength, "device");
  if (in.modules().size() > kMaxModules) c.Fail("modules: more than 16");
  for (const auto& m : in.modules()) c.String(S(m.name()), kMaxModuleNameLength, "modules[]");
  c.Finite(in.haptic_rate_hz(), "haptic_rate_hz");
  c.Finite(in.mirror_rate_hz(), "mirror_rate_hz");
  c.Finite(in.skill(), "skill");
  c.Range(in.haptic_rate_hz(), 0.0, 100e3, "haptic_rate_hz");
  c.Range(in.mirror_rate_hz(), 0.0, 10e3, "mirror_rate_hz");
  out.trainee = S(in.trainee());
  out.scene = S(in.scene());
  out.modules.clear();
  for (const auto& m : in.modules()) out.modules.push_back(S(m.name()));
  out.build = S(in.build());
  out.haptic_rate_hz = in.haptic_rate_hz();
  out.mirror_rate_hz = in.mirror_rate_hz();
  out.skill = in.skill();
  out.device = S(in.device());
  out.seed = in.seed();
  out.scene_hash = in.scene_hash();
  return c.ok();
}

// ---- DeviceInput ----
void ToMsg(const DeviceInput& in, msg::DeviceInput& out) {
  HeaderToMsg(in.header, out);
  out.p_WT(V(in.p_WT));
  out.q_WT(Q(in.q_WT));
  out.gripper(in.gripper);
  out.buttons(in.buttons);
  out.state_hash(in.state_hash);
  out.p_WT2(V(in.p_WT2));
  out.q_WT2(Q(in.q_WT2));
  out.gripper2(in.gripper2);
  out.buttons2(in.buttons2);
}

bool FromMsg(const msg::DeviceInput& in, DeviceInput& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  c.Finite(in.p_WT(), "p_WT");
  c.Unit(in.q_WT(), "q_WT");
  c.Finite(in.gripper(), "gripper");
  c.Range(in.p_WT(), kMaxAbsPosition_m, "p_WT");
  c.Range(in.gripper(), 0.0, 1.0, "gripper");
  out.p_WT = V(in.p_WT());
  out.q_WT = Q(in.q_WT());
  out.gripper = in.gripper();
  out.buttons = in.buttons();
  out.state_hash = in.state_hash();
  // A one-handed sender may leave the second hand all zero: the identity rotation then.
  const auto& q2 = in.q_WT2();
  const bool no_second = q2[0] == 0 && q2[1] == 0 && q2[2] == 0 && q2[3] == 0;
  c.Finite(in.p_WT2(), "p_WT2");
  if (!no_second) c.Unit(q2, "q_WT2");
  c.Finite(in.gripper2(), "gripper2");
  out.p_WT2 = V(in.p_WT2());
  out.q_WT2 = no_second ? Eigen::Quaterniond::Identity() : Q(q2);
  out.gripper2 = in.gripper2();
  out.buttons2 = in.buttons2();
  return c.ok();
}

namespace {

// The active-cue mask: bit k of the message is the IDL's CueKind value k, bit k of the plain
// type cues::CueKind k; each set bit is converted by the kind's name, so neither side depends
// on the other's numbering. Returns false for a message bit that names no kind.
std::uint32_t ActiveCuesToMsg(std::uint32_t plain) {
  std::uint32_t out = 0;
  for (std::uint32_t k = 0; k < cues::kCueKindCount; ++k) {
    if ((plain >> k) & 1u) out |= 1u << static_cast<std::uint32_t>(CueKindToMsg(cues::CueKind(k)));
  }
  return out;
}

bool ActiveCuesFromMsg(std::uint32_t bits, std::uint32_t* plain) {
  *plain = 0;
  for (std::uint32_t k = 0; k < 32; ++k) {
    if (!((bits >> k) & 1u)) continue;
    cues::CueKind kind;
    if (!CueKindFromMsg(static_cast<msg::CueKind>(k), &kind)) return false;
    *plain |= 1u << static_cast<std::uint32_t>(kind);
  }
  return true;
}

}  // namespace

namespace {

// Needle clearance and tissue step statuses cross by name.
msg::NeedleClearanceStatus ClearanceStatusToMsg(ClearanceStatus s) {
  switch (s) {
    case ClearanceStatus::kOk:
      return msg::CLEARANCE_OK;
    case ClearanceStatus::kEmptyRange:
      return msg::CLEARANCE_EMPTY_RANGE;
    case ClearanceStatus::kInvalidInput:
      return msg::CLEARANCE_INVALID_INPUT;
  }
  MICRODEX_CHECK(false);
  return msg::CLEARANCE_INVALID_INPUT;
}

bool ClearanceStatusFromMsg(msg::NeedleClearanceStatus in, ClearanceStatus* out) {
  switch (in) {
    case msg::CLEARANCE_OK:
      *out = ClearanceStatus::kOk;
      return true;
    case msg::CLEARANCE_EMPTY_RANGE:
      *out = ClearanceStatus::kEmptyRange;
      return true;
    case msg::CLEARANCE_INVALID_INPUT:
      *out = ClearanceStatus::kInvalidInput;
      return true;
  }
  return false;
}

msg::TissueStepStatus TissueStatusToMsg(TissueStepStatus s) {
  switch (s) {
    case TissueStepStatus::kOk:
      return msg::TISSUE_OK;
    case TissueStepStatus::kNoContact:
      return msg::TISSUE_NO_CONTACT;
    case TissueStepStatus::kBadInput:
      return msg::TISSUE_BAD_INPUT;
    case TissueStepStatus::kTooManyContacts:
      return msg::TISSUE_TOO_MANY_CONTACTS;
    case TissueStepStatus::kNotConverged:
      return msg::TISSUE_NOT_CONVERGED;
    case TissueStepStatus::kFactorisationFailed:
      return msg::TISSUE_FACTORISATION_FAILED;
    case TissueStepStatus::kNonFinite:
      return msg::TISSUE_NON_FINITE;
  }
  MICRODEX_CHECK(false);
  return msg::TISSUE_NON_FINITE;
}

bool TissueStatusFromMsg(msg::TissueStepStatus in, TissueStepStatus* out) {
  switch (in) {
    case msg::TISSUE_OK:
      *out = TissueStepStatus::kOk;
      return true;
    case msg::TISSUE_NO_CONTACT:
      *out = TissueStepStatus::kNoContact;
      return true;
    case msg::TISSUE_BAD_INPUT:
      *out = TissueStepStatus::kBadInput;
      return true;
    case msg::TISSUE_TOO_MANY_CONTACTS:
      *out = TissueStepStatus::kTooManyContacts;
      return true;
    case msg::TISSUE_NOT_CONVERGED:
      *out = TissueStepStatus::kNotConverged;
      return true;
    case msg::TISSUE_FACTORISATION_FAILED:
      *out = TissueStepStatus::kFactorisationFailed;
      return true;
    case msg::TISSUE_NON_FINITE:
      *out = TissueStepStatus::kNonFinite;
      return true;
  }
  return false;
}

}  // namespace

// ---- ToolState ----
void ToMsg(const ToolState& in, msg::ToolState& out) {
  HeaderToMsg(in.header, out);
  out.p_WT(V(in.p_WT));
  out.q_WT(Q(in.q_WT));
  out.f_T_W(V(in.f_T_W));
  out.tremor_rms_m(in.tremor_rms_m);
  out.active_cues(ActiveCuesToMsg(in.active_cues));
  out.has_second_tool(in.has_second_tool ? 1 : 0);
  out.p_WT2(V(in.p_WT2));
  out.q_WT2(Q(in.q_WT2));
  out.f_T2_W(V(in.f_T2_W));
  const auto n = static_cast<std::size_t>(std::clamp<int>(in.stitch_count, 0, kMaxStitches));
  out.stitch_azimuth_rad().assign(in.stitch_azimuth_rad.begin(), in.stitch_azimuth_rad.begin() + n);
  out.stitch_bite_m().assign(in.stitch_bite_m.begin(), in.stitch_bite_m.begin() + n);
}

bool FromMsg(const msg::ToolState& in, ToolState& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  c.Finite(in.p_WT(), "p_WT");
  c.Unit(in.q_WT(), "q_WT");
  c.Finite(in.f_T_W(), "f_T_W");
  c.Finite(in.tremor_rms_m(), "tremor_rms_m");
  out.p_WT = V(in.p_WT());
  out.q_WT = Q(in.q_WT());
  out.f_T_W = V(in.f_T_W());
  out.tremor_rms_m = in.tremor_rms_m();
  if (!ActiveCuesFromMsg(in.active_cues(), &out.active_cues)) {
    c.Fail("active_cues: a bit that names no cue kind");
  }
  if (in.has_second_tool() > 1) c.Fail("has_second_tool: expected 0 or 1");
  out.has_second_tool = in.has_second_tool() == 1;
  if (out.has_second_tool) {
    c.Finite(in.p_WT2(), "p_WT2");
    c.Unit(in.q_WT2(), "q_WT2");
    c.Finite(in.f_T2_W(), "f_T2_W");
    out.p_WT2 = V(in.p_WT2());
    out.q_WT2 = Q(in.q_WT2());
    out.f_T2_W = V(in.f_T2_W());
  } else {
    out.p_WT2.setZero();
    out.q_WT2.setIdentity();
    out.f_T2_W.setZero();
  }
  const std::vector<float>& az = in.stitch_azimuth_rad();
  const std::vector<float>& bite = in.stitch_bite_m();
  out.stitch_count = 0;
  if (az.size() != bite.size() || az.size() > kMaxStitches) {
    c.Fail("stitch_azimuth_rad, stitch_bite_m: expected as many of each, at most " +
           std::to_string(kMaxStitches));
  } else {
    for (std::size_t i = 0; i < az.size(); ++i) {
      // Azimuth in [0, 2π] (float rounding may reach 2π itself); a bite where a tool tip can
      // be (the module records wherever the trainee places it).
      if (!(az[i] >= 0.0F && az[i] <= 6.2832F)) c.Fail("stitch_azimuth_rad: outside [0, 2 pi)");
      if (!(std::abs(bite[i]) <= 1.0F)) c.Fail("stitch_bite_m: not finite or beyond 1 m");
      out.stitch_azimuth_rad[i] = az[i];
      out.stitch_bite_m[i] = bite[i];
    }
    if (c.ok()) out.stitch_count = static_cast<int>(az.size());
  }
  return c.ok();
}

// ---- NeedleState ----
void ToMsg(const NeedleState& in, msg::NeedleState& out) {
  HeaderToMsg(in.header, out);
  out.p_WN(V(in.p_WN));
  out.q_WN(Q(in.q_WN));
  out.clearance_m(in.clearance_m);
  out.contact(in.contact ? 1 : 0);
  out.s_rad(in.s_rad);
  out.p_WD(V(in.p_WD));
  out.p_WB(V(in.p_WB));
  out.status(ClearanceStatusToMsg(in.status));
}

bool FromMsg(const msg::NeedleState& in, NeedleState& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  c.Finite(in.p_WN(), "p_WN");
  c.Unit(in.q_WN(), "q_WN");
  c.Flag(in.contact(), "contact");
  ClearanceStatus status = ClearanceStatus::kInvalidInput;
  if (!ClearanceStatusFromMsg(in.status(), &status)) c.Fail("status: not a clearance status");
  // Clearance and the closest points are NaN when the status says there is none.
  if (status == ClearanceStatus::kOk) {
    c.Finite(in.clearance_m(), "clearance_m");
    c.Finite(in.s_rad(), "s_rad");
    c.Finite(in.p_WD(), "p_WD");
    c.Finite(in.p_WB(), "p_WB");
  }
  out.p_WN = V(in.p_WN());
  out.q_WN = Q(in.q_WN());
  out.clearance_m = in.clearance_m();
  out.contact = in.contact() == 1;
  out.s_rad = in.s_rad();
  out.p_WD = V(in.p_WD());
  out.p_WB = V(in.p_WB());
  out.status = status;
  return c.ok();
}

// ---- ThreadState ----
void ToMsg(const ThreadState& in, msg::ThreadState& out) {
  HeaderToMsg(in.header, out);
  MICRODEX_CHECK(in.nodes.size() <= kMaxThreadNodes && in.knot.size() <= kMaxModuleNameLength);
  out.nodes().resize(in.nodes.size());
  for (std::size_t i = 0; i < in.nodes.size(); ++i) {
    out.nodes()[i].x(in.nodes[i].x());
    out.nodes()[i].y(in.nodes[i].y());
    out.nodes()[i].z(in.nodes[i].z());
  }
  out.knot(in.knot);
  out.max_strain(in.max_strain);
  out.grasped_node(in.grasped_node);
  out.f_T_W(V(in.f_T_W));
}

bool FromMsg(const msg::ThreadState& in, ThreadState& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  if (in.nodes().size() > kMaxThreadNodes) c.Fail("nodes: more than kMaxThreadNodes");
  c.String(S(in.knot()), kMaxModuleNameLength, "knot");
  c.Finite(in.max_strain(), "max_strain");
  c.Finite(in.f_T_W(), "f_T_W");
  if (in.grasped_node() < -1 || in.grasped_node() >= static_cast<std::int32_t>(in.nodes().size())) {
    c.Fail("grasped_node: expected -1 or a node index");
  }
  if (!c.ok()) return false;
  out.nodes.resize(in.nodes().size());
  for (std::size_t i = 0; i < in.nodes().size(); ++i) {
    const auto& n = in.nodes()[i];
    c.Finite(n.x(), "nodes[].x");
    c.Finite(n.y(), "nodes[].y");
    c.Finite(n.z(), "nodes[].z");
    out.nodes[i] = {n.x(), n.y(), n.z()};
  }
  out.knot = S(in.knot());
  out.max_strain = in.max_strain();
  out.grasped_node = in.grasped_node();
  out.f_T_W = V(in.f_T_W());
  return c.ok();
}

// ---- TissueState ----
void ToMsg(const TissueState& in, msg::TissueState& out) {
  HeaderToMsg(in.header, out);
  MICRODEX_CHECK(in.displacement_m.size() <= kMaxTissueNodes &&
                 in.displacement_m.size() ==
                     static_cast<std::size_t>(in.nodes_x) * static_cast<std::size_t>(in.nodes_y));
  out.p_WS(V(in.p_WS));
  out.q_WS(Q(in.q_WS));
  out.length_x_m(in.length_x_m);
  out.length_y_m(in.length_y_m);
  out.nodes_x(in.nodes_x);
  out.nodes_y(in.nodes_y);
  out.mesh_revision(in.mesh_revision);
  out.unknowns(in.unknowns);
  out.max_displacement_m(in.max_displacement_m);
  out.status(TissueStatusToMsg(in.status));
  out.displacement_m(in.displacement_m);
}

bool FromMsg(const msg::TissueState& in, TissueState& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  if (in.displacement_m().size() > kMaxTissueNodes) c.Fail("displacement_m: too many nodes");
  if (static_cast<std::uint64_t>(in.nodes_x()) * in.nodes_y() != in.displacement_m().size()) {
    c.Fail("nodes_x * nodes_y: expected the length of displacement_m");
  }
  c.Finite(in.p_WS(), "p_WS");
  c.Unit(in.q_WS(), "q_WS");
  if (!(in.length_x_m() > 0 && std::isfinite(in.length_x_m()))) c.Fail("length_x_m: expected > 0");
  if (!(in.length_y_m() > 0 && std::isfinite(in.length_y_m()))) c.Fail("length_y_m: expected > 0");
  c.Finite(in.max_displacement_m(), "max_displacement_m");
  TissueStepStatus status = TissueStepStatus::kNonFinite;
  if (!TissueStatusFromMsg(in.status(), &status)) c.Fail("status: not a tissue step status");
  if (!c.ok()) return false;
  for (float w : in.displacement_m()) c.Finite(w, "displacement_m[]");
  out.p_WS = V(in.p_WS());
  out.q_WS = Q(in.q_WS());
  out.length_x_m = in.length_x_m();
  out.length_y_m = in.length_y_m();
  out.nodes_x = in.nodes_x();
  out.nodes_y = in.nodes_y();
  out.mesh_revision = in.mesh_revision();
  out.unknowns = in.unknowns();
  out.max_displacement_m = in.max_displacement_m();
  out.status = status;
  out.displacement_m = in.displacement_m();
  return c.ok();
}

// ---- Telemetry ----
void ToMsg(const Telemetry& in, msg::Telemetry& out) {
  HeaderToMsg(in.header, out);
  MICRODEX_CHECK(in.modules.size() <= kMaxTelemetryModules);
  out.window_s(in.window_s);
  out.ticks(in.ticks);
  out.period_mean_s(in.period_mean_s);
  out.period_p99_s(in.period_p99_s);
  out.period_max_s(in.period_max_s);
  out.overruns(in.overruns);
  out.ring_dropped(in.ring_dropped);
  out.realtime(in.realtime ? 1 : 0);
  out.has_state_hash(in.has_state_hash ? 1 : 0);
  out.state_hash_step(in.state_hash_step);
  out.state_hash(in.state_hash);
  out.cues_invalid(in.cues_invalid);
  out.device_samples_invalid(in.device_samples_invalid);
  out.modules().resize(in.modules.size());
  for (std::size_t i = 0; i < in.modules.size(); ++i) {
    const auto& m = in.modules[i];
    CheckModuleName(m.name);
    CheckModuleName(m.error_kind);
    auto& o = out.modules()[i];
    o.name(m.name);
    o.step_time_mean_s(m.step_time_mean_s);
    o.step_time_max_s(m.step_time_max_s);
    o.error_estimate(m.error_estimate);
    o.error_kind(m.error_kind);
    o.warnings(m.warnings);
  }
}

bool FromMsg(const msg::Telemetry& in, Telemetry& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  c.Finite(in.window_s(), "window_s");
  c.Finite(in.period_mean_s(), "period_mean_s");
  c.Finite(in.period_p99_s(), "period_p99_s");
  c.Finite(in.period_max_s(), "period_max_s");
  c.Flag(in.realtime(), "realtime");
  c.Flag(in.has_state_hash(), "has_state_hash");
  if (in.modules().size() > kMaxTelemetryModules) c.Fail("modules: too many");
  if (!c.ok()) return false;
  out.window_s = in.window_s();
  out.ticks = in.ticks();
  out.period_mean_s = in.period_mean_s();
  out.period_p99_s = in.period_p99_s();
  out.period_max_s = in.period_max_s();
  out.overruns = in.overruns();
  out.ring_dropped = in.ring_dropped();
  out.has_state_hash = in.has_state_hash() != 0;
  out.state_hash_step = in.state_hash_step();
  out.state_hash = in.state_hash();
  out.cues_invalid = in.cues_invalid();
  out.device_samples_invalid = in.device_samples_invalid();
  out.realtime = in.realtime() == 1;
  out.modules.resize(in.modules().size());
  for (std::size_t i = 0; i < in.modules().size(); ++i) {
    const auto& m = in.modules()[i];
    c.String(S(m.name()), kMaxModuleNameLength, "modules[].name");
    c.String(S(m.error_kind()), kMaxModuleNameLength, "modules[].error_kind");
    // The error estimate may be NaN when a module has none in the window.
    c.Finite(m.step_time_mean_s(), "modules[].step_time_mean_s");
    c.Finite(m.step_time_max_s(), "modules[].step_time_max_s");
    out.modules[i] = ModuleTelemetry{S(m.name()),        m.step_time_mean_s(), m.step_time_max_s(),
                                     m.error_estimate(), S(m.error_kind()),    m.warnings()};
  }
  return c.ok();
}

std::uint32_t ActiveCuesToWire(std::uint32_t plain) { return ActiveCuesToMsg(plain); }
bool ActiveCuesFromWire(std::uint32_t bits, std::uint32_t* plain) {
  return ActiveCuesFromMsg(bits, plain);
}

// ---- CueCommand ----
void ToMsg(const CueCommand& in, msg::CueCommand& out) {
  HeaderToMsg(in.header, out);

  MICRODEX_CHECK(in.issuer.size() <= kMaxIdLength);
  out.cue_id(in.cue_id);
  out.kind(CueKindToMsg(in.kind));
  out.param(in.param);
  out.issuer(in.issuer);
  out.off(in.off);
  MICRODEX_CHECK(in.station_session.size() <= kMaxIdLength);
  MICRODEX_CHECK(in.condition_size <= kMaxConditionSize);
  out.station_session(in.station_session);
  out.condition_size(in.condition_size);
}

bool FromMsg(const msg::CueCommand& in, CueCommand& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  if (!CueKindFromMsg(in.kind(), &out.kind)) c.Fail("kind: unknown cue kind");
  if (!in.off()) c.Finite(in.param(), "param");
  c.String(S(in.issuer()), kMaxIdLength, "issuer");
  out.cue_id = in.cue_id();
  out.off = in.off();
  out.param = in.off() ? 0.0 : in.param();
  out.issuer = S(in.issuer());
  c.String(S(in.station_session()), kMaxIdLength, "station_session");
  if (in.condition_size() > kMaxConditionSize) {
    c.Fail("condition_size: more than " + std::to_string(kMaxConditionSize));
  }
  out.station_session = S(in.station_session());
  out.condition_size = in.condition_size();
  return c.ok();
}

// ---- TaskEvent ----
void ToMsg(const TaskEvent& in, msg::TaskEvent& out) {
  HeaderToMsg(in.header, out);
  MICRODEX_CHECK(in.text.size() <= kMaxTextLength);
  out.kind(TaskEventKindToMsg(in.kind));
  out.cue_id(in.cue_id);
  out.value(in.value);
  out.text(in.text);
}

bool FromMsg(const msg::TaskEvent& in, TaskEvent& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  if (!TaskEventKindFromMsg(in.kind(), &out.kind)) c.Fail("kind: unknown event kind");
  c.String(S(in.text()), kMaxTextLength, "text");
  out.cue_id = in.cue_id();
  out.value = in.value();
  out.text = S(in.text());
  return c.ok();
}

// ---- Score ----
void ToMsg(const Score& in, msg::Score& out) {
  HeaderToMsg(in.header, out);
  out.is_final(in.is_final ? 1 : 0);
  out.duration_s(in.duration_s);
  out.time_in_contact_s(in.time_in_contact_s);
  out.contacts(in.contacts);
  out.mean_clearance_m(in.mean_clearance_m);
  out.min_clearance_m(in.min_clearance_m);
  out.path_length_m(in.path_length_m);
  out.ideal_path_length_m(in.ideal_path_length_m);
  out.tremor_rms_m(in.tremor_rms_m);
  out.score(in.score);
  CheckModuleName(in.task);
  MICRODEX_CHECK(in.terms.size() <= kMaxScoreTerms);
  out.task(in.task);
  out.outcome(in.outcome);
  out.deviation_mean_m(in.deviation_mean_m);
  out.progress(in.progress);
  out.terms().resize(in.terms.size());
  for (std::size_t i = 0; i < in.terms.size(); ++i) {
    const ScoreTerm& t = in.terms[i];
    CheckModuleName(t.metric);
    msg::ScoreTerm& o = out.terms()[i];
    o.metric(t.metric);
    o.value(t.value);
    o.limit(t.limit);
    o.weight(t.weight);
    o.points(t.points);
  }
}

bool FromMsg(const msg::Score& in, Score& out, std::string* why) {
  Checker c(why);
  HeaderFromMsg(in, out.header, c);
  c.Flag(in.is_final(), "is_final");
  c.Finite(in.duration_s(), "duration_s");
  c.Finite(in.time_in_contact_s(), "time_in_contact_s");
  c.Finite(in.path_length_m(), "path_length_m");
  c.Finite(in.ideal_path_length_m(), "ideal_path_length_m");
  c.Finite(in.tremor_rms_m(), "tremor_rms_m");
  c.Finite(in.score(), "score");
  c.String(S(in.task()), kMaxModuleNameLength, "task");
  if (in.outcome() > 2) c.Fail("outcome: expected 0, 1 or 2");
  c.Finite(in.progress(), "progress");
  if (in.terms().size() > kMaxScoreTerms) c.Fail("terms: more than 12");
  for (const auto& t : in.terms()) {
    c.String(S(t.metric()), kMaxModuleNameLength, "terms[].metric");
    c.Finite(t.limit(), "terms[].limit");
    c.Finite(t.weight(), "terms[].weight");
    c.Finite(t.points(), "terms[].points");
  }
  if (!c.ok()) return false;
  out.is_final = in.is_final() == 1;
  out.duration_s = in.duration_s();
  out.time_in_contact_s = in.time_in_contact_s();
  out.contacts = in.contacts();
  out.mean_clearance_m = in.mean_clearance_m();
  out.min_clearance_m = in.min_clearance_m();
  out.path_length_m = in.path_length_m();
  out.ideal_path_length_m = in.ideal_path_length_m();
  out.tremor_rms_m = in.tremor_rms_m();
  out.score = in.score();
  out.task = S(in.task());
  out.outcome = in.outcome();
  out.deviation_mean_m = in.deviation_mean_m();
  out.progress = in.progress();
  out.terms.clear();
  for (const auto& t : in.terms()) {
    out.terms.push_back({S(t.metric()), t.value(), t.limit(), t.weight(), t.points()});
  }
  return c.ok();
}

}  // namespace microdex::net
