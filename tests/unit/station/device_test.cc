// Devices: the fault guard (a driver that stops, sends NaN or jumps: the last valid sample is
// held; valid samples resume it), the workspace mapping (motion scaling, the clutch, the force
// into the device frame, limited), CSV playback (and its errors by file, line and column), and
// the station under a device fault: the tool held, the force ramped to zero at the limiter's
// rate, the fault in the state and the snapshot, the period kept, the run resumed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "common/base/input_error.h"
#include "common/cues/force_limits.h"
#include "station/device_driver.h"
#include "station/device_guard.h"
#include "station/device_mapping.h"
#include "station/haptic_loop.h"
#include "station/playback_device.h"

namespace microdex::station {
namespace {

constexpr double kTol_m = 1e-12;

RawDeviceSample At(double x) {
  RawDeviceSample s;
  s.p_D = Eigen::Vector3d(x, 0, 0);
  return s;
}

TEST(DeviceGuard, TimeoutNaNAndJumpHoldTheLastValidSampleUntilValidSamplesReturn) {
  DeviceGuard g;
  DeviceFault f{};
  bool resumed = false;
  RawDeviceSample s = At(1e-3);
  EXPECT_EQ(g.Step(&s, &f, &resumed).p_D.x(), 1e-3);
  EXPECT_EQ(f, DeviceFault::kNone);
  // Nine steps without a sample: still fine (the last sample repeats); the tenth: a timeout.
  for (int i = 0; i < 9; ++i) {
    g.Step(nullptr, &f, &resumed);
    EXPECT_EQ(f, DeviceFault::kNone) << i;
  }
  EXPECT_EQ(g.Step(nullptr, &f, &resumed).p_D.x(), 1e-3);
  EXPECT_EQ(f, DeviceFault::kTimeout);
  // Samples again: held until five consistent ones, then resumed at the new position.
  for (int i = 0; i < 4; ++i) {
    s = At(2e-3 + i * 1e-5);
    EXPECT_EQ(g.Step(&s, &f, &resumed).p_D.x(), 1e-3);
    EXPECT_EQ(f, DeviceFault::kTimeout);
    EXPECT_FALSE(resumed);
  }
  s = At(2.04e-3);
  EXPECT_NEAR(g.Step(&s, &f, &resumed).p_D.x(), 2.04e-3, kTol_m);
  EXPECT_EQ(f, DeviceFault::kNone);
  EXPECT_TRUE(resumed);
  // NaN.
  s = At(std::numeric_limits<double>::quiet_NaN());
  EXPECT_NEAR(g.Step(&s, &f, &resumed).p_D.x(), 2.04e-3, kTol_m);
  EXPECT_EQ(f, DeviceFault::kNonFinite);
  RawDeviceSample bad_q = At(2.04e-3);
  bad_q.q_D = Eigen::Quaterniond(0, 0, 0, 0);
  g.Step(&bad_q, &f, &resumed);
  EXPECT_EQ(f, DeviceFault::kNonFinite) << "a zero quaternion is no orientation";
  for (int i = 0; i < 5; ++i) {
    s = At(2.04e-3);
    g.Step(&s, &f, &resumed);
  }
  EXPECT_EQ(f, DeviceFault::kNone);
  // A jump of 5 cm in one sample.
  s = At(0.05);
  EXPECT_NEAR(g.Step(&s, &f, &resumed).p_D.x(), 2.04e-3, kTol_m);
  EXPECT_EQ(f, DeviceFault::kJump);
  for (int i = 0; i < 4; ++i) {
    s = At(0.05);
    g.Step(&s, &f, &resumed);
  }
  EXPECT_EQ(f, DeviceFault::kNone) << "five consistent samples (the jump's and four) resume";
  EXPECT_TRUE(resumed);
  DeviceGuardDef bad;
  bad.max_jump_m = std::nan("");
  EXPECT_THROW(DeviceGuard{bad}, std::invalid_argument);
}

TEST(DeviceMapping, ScalingClutchAndForce) {
  DeviceMappingDef def;
  def.motion_scale = 0.1;
  def.p_W_centre = Eigen::Vector3d(0.01, 0.02, 0.03);
  def.R_WD = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  def.max_force_N = 1.0;
  DeviceMapping m(def);
  RawDeviceSample s;
  EXPECT_TRUE(m.Map(s).translation().isApprox(def.p_W_centre, kTol_m));
  s.p_D = Eigen::Vector3d(0.01, 0, 0);  // 10 mm along the device's x = world y
  Eigen::Vector3d p = m.Map(s).translation();
  EXPECT_NEAR(p.y() - def.p_W_centre.y(), 1e-3, kTol_m) << "a tenth of the hand's motion";
  EXPECT_NEAR(p.x() - def.p_W_centre.x(), 0, kTol_m);
  // Clutch: the hand moves back 30 mm, the tool stays.
  s.buttons = def.clutch_button;
  s.p_D = Eigen::Vector3d(-0.02, 0, 0);
  EXPECT_TRUE(m.Map(s).translation().isApprox(p, kTol_m));
  EXPECT_TRUE(m.clutched());
  // Released: the tool continues from where it was.
  s.buttons = 0;
  s.p_D = Eigen::Vector3d(-0.01, 0, 0);
  const Eigen::Vector3d p2 = m.Map(s).translation();
  EXPECT_NEAR(p2.y() - p.y(), 1e-3, kTol_m);
  // Force: rotated into the device frame, limited.
  const Eigen::Vector3d f_D = m.ForceToDevice(Eigen::Vector3d(0, 0.5, 0));
  EXPECT_TRUE(f_D.isApprox(Eigen::Vector3d(0.5, 0, 0), 1e-12)) << f_D.transpose();
  EXPECT_NEAR(m.ForceToDevice(Eigen::Vector3d(0, 0, 30)).norm(), 1.0, 1e-12);
  EXPECT_EQ(m.ForceToDevice(Eigen::Vector3d(std::nan(""), 0, 0)), Eigen::Vector3d::Zero());
  DeviceMappingDef bad;
  bad.motion_scale = 0;
  EXPECT_THROW(DeviceMapping{bad}, std::invalid_argument);
}

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(DeviceMapping, LoadedFromAFileWithDefaultsErrorsNamingFileLineAndField) {
  DeviceMappingDef defaults;
  defaults.motion_scale = 1.0 / 15;  // the scene's magnification
  defaults.max_force_N = 2.0;
  const std::string path = WriteTemp("microdex_device_map.yaml", R"(# a Touch turned on its side
rpy_rad: [0, 0, 1.5707963267948966]
motion_scale: 0.05
max_torque_Nm: 0
clutch_button: 3
second:
  force_scale: 0.5
)");
  const DeviceMappingDef first = LoadDeviceMapping(path, 0, defaults);
  EXPECT_TRUE((first.R_WD * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_EQ(first.motion_scale, 0.05);
  EXPECT_EQ(first.max_force_N, 2.0) << "not in the file: the default";
  EXPECT_EQ(first.max_torque_Nm, 0.0);
  EXPECT_EQ(first.clutch_button, 1u << 3);
  EXPECT_EQ(first.force_scale, 1.0);
  const DeviceMappingDef second = LoadDeviceMapping(path, 1, defaults);
  EXPECT_EQ(second.force_scale, 0.5);
  EXPECT_EQ(second.motion_scale, defaults.motion_scale) << "the second section only";
  EXPECT_TRUE(second.R_WD.isIdentity(0));
  auto error = [&](const std::string& text) {
    const std::string bad = WriteTemp("microdex_device_map_bad.yaml", text);
    try {
      LoadDeviceMapping(bad, 0, defaults);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string unknown = error("motion_scale: 0.1\nmotion_scal: 0.2\n");
  EXPECT_NE(unknown.find("microdex_device_map_bad.yaml:2"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("motion_scal"), std::string::npos) << unknown;
  const std::string zero = error("force_scale: 1\nmotion_scale: 0\n");
  EXPECT_NE(zero.find("motion_scale"), std::string::npos) << zero;
  EXPECT_NE(error("clutch_button: 40\n").find("clutch_button"), std::string::npos);
  EXPECT_NE(error("rpy_rad: [0, .nan, 0]\n").find("rpy_rad"), std::string::npos);
}

TEST(PlaybackDevice, PlaysRowsInOrderThenHoldsAndFlagsBadRows) {
  const std::string path = WriteTemp("microdex_playback_test.csv",
                                     "p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons\n"
                                     "0.001,0,0,1,0,0,0,0,0\n"
                                     "0.002,0,0,1,0,0,0,0.5,1\n"
                                     "nan,0,0,1,0,0,0,0,0\n");
  PlaybackDevice d(path);
  EXPECT_EQ(d.rows(), 3u);
  EXPECT_NEAR(d.Read(0).X_WT.translation().x(), 0.001, kTol_m);
  const DeviceSample s1 = d.Read(1);
  EXPECT_NEAR(s1.X_WT.translation().x(), 0.002, kTol_m);
  EXPECT_EQ(s1.gripper, 0.5);
  EXPECT_EQ(s1.buttons, 1u);
  const DeviceSample s2 = d.Read(2);
  EXPECT_EQ(s2.fault, DeviceFault::kNonFinite);
  EXPECT_NEAR(s2.X_WT.translation().x(), 0.002, kTol_m) << "held";
  std::remove(path.c_str());
  struct Bad {
    const char* text;
    const char* expected;  // after "PATH:"
  };
  for (const Bad& b :
       {Bad{"x,y\n1,2\n", "1: header: expected p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons"},
        Bad{"p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons\n0,0,0,1,0,0,0,0,0\n0,0,zero,1,0,0,0,0,"
            "0\n",
            "3: p_z: 'zero' is not a number"},
        Bad{"p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons\n0,0,0,1,0,0,0,0\n",
            "2: expected 9 columns"},
        Bad{"p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons\n0,0,0,1,0,0,0,0,1.5\n",
            "2: buttons: expected an integer bit mask"},
        Bad{"p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons\n", "1: no rows after the header"}}) {
    const std::string p = WriteTemp("microdex_playback_bad.csv", b.text);
    try {
      PlaybackDevice bad(p);
      ADD_FAILURE() << b.text << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), p + ":" + b.expected);
    }
    std::remove(p.c_str());
  }
  EXPECT_THROW(PlaybackDevice("/nonexistent/x.csv"), InputError);
}

// A device that follows a slow sine, then misbehaves from step `fault_from` for `fault_steps`
// steps in the given way, then behaves again; behind the same guard as the DDS bridge.
class ScriptedDevice final : public Device {
 public:
  ScriptedDevice(const Eigen::Vector3d& p0, int fault_from, int fault_steps, DriverFault mode)
      : p0_(p0), from_(fault_from), steps_(fault_steps), mode_(mode) {}
  DeviceSample Read(std::uint64_t step) override {
    const auto k = static_cast<int>(step);
    const bool bad = k >= from_ && k < from_ + steps_;
    RawDeviceSample raw;
    raw.p_D = p0_ + Eigen::Vector3d(2e-4 * std::sin(1e-3 * k), 0, 0);
    if (bad && mode_ == DriverFault::kNaN) raw.p_D.x() = std::numeric_limits<double>::quiet_NaN();
    if (bad && mode_ == DriverFault::kJump) raw.p_D.x() += 0.05;
    DeviceFault fault{};
    bool resumed = false;
    const RawDeviceSample& s =
        guard_.Step(bad && mode_ == DriverFault::kStop ? nullptr : &raw, &fault, &resumed);
    DeviceSample out;
    out.X_WT.translation() = s.p_D;
    out.fault = fault;
    return out;
  }
  void WriteForce(const Eigen::Vector3d&) override {}

 private:
  Eigen::Vector3d p0_;
  int from_, steps_;
  DriverFault mode_;
  DeviceGuard guard_;
};

scene::SceneModel NeedleScene() {
  return scene::ParseScene(R"(
name: test-needle
modules: [needle]
vessel: {core_radius_m: 5.0e-3, tube_radius_m: 0.5e-3, segment_angle_rad: 4.71238898}
needle: {radius_m: 5.0e-3, sweep_rad: 1.04719755}
task: {pass_duration_s: 2.0, start_azimuth_rad: 0.2, end_azimuth_rad: 3.3}
haptic: {rate_hz: 1000, max_force_N: 1.0, wall_stiffness_N_per_m: 1000}
)",
                           "inline");
}

TEST(DeviceFaults, ToolHeldForceRampedToZeroEventFlaggedAndResumed) {
  for (DriverFault mode : {DriverFault::kStop, DriverFault::kNaN, DriverFault::kJump}) {
    SCOPED_TRACE(static_cast<int>(mode));
    const scene::SceneModel scene = NeedleScene();
    // 3 mm off the path: the convergent field pushes with its saturated force.
    const Eigen::Vector3d p0 =
        scene.CalcIdealToolPose(0).translation() + Eigen::Vector3d(0, 0, 3e-3);
    constexpr int kFrom = 500, kSteps = 100;
    ScriptedDevice device(p0, kFrom, kSteps, mode);
    StationRings rings;
    rt::ManualClock clock;
    HapticLoopConfig config;
    config.stop_at_task_end = false;
    HapticLoop loop(scene, device, rings, clock, config);
    ASSERT_TRUE(rings.cues.TryPush({1, cues::CueKind::kConvergentField, 2000, 0, false}));
    std::vector<TickSnapshot> snaps;
    const std::atomic<bool> stop{false};
    while (loop.step() < 900) {
      loop.Run(stop, std::min<std::uint64_t>(900, loop.step() + 200));
      TickSnapshot t;
      while (rings.snapshots.TryPop(t)) snaps.push_back(t);
    }
    ASSERT_EQ(snaps.size(), 900u);
    const double max_step = cues::kMaxForceRate_N_per_s * loop.dt_s();
    const int ramp_steps = static_cast<int>(std::ceil(scene.haptic.max_force_N / max_step));
    // The fault is seen from the step it starts (NaN, jump) or 10 steps later (timeout).
    const int seen = mode == DriverFault::kStop ? kFrom + 9 : kFrom;
    EXPECT_EQ(snaps[seen - 1].device_fault, 0);
    EXPECT_NE(snaps[seen].device_fault, 0);
    const double f_before =
        std::hypot(snaps[seen - 1].f_T_W[0], snaps[seen - 1].f_T_W[1], snaps[seen - 1].f_T_W[2]);
    EXPECT_GT(f_before, 0.5) << "the field pushed before the fault";
    // A jump is over once five consistent samples follow it (the jump's own and four more; the
    // bridge then re-centres its mapping); the others last as long as the driver misbehaves.
    const int fault_end = mode == DriverFault::kJump ? kFrom + 4 : kFrom + kSteps;
    const int resumed_at = mode == DriverFault::kJump ? fault_end : fault_end + 4;
    EXPECT_NE(snaps[resumed_at - 1].device_fault, 0);
    EXPECT_EQ(snaps[resumed_at].device_fault, 0) << "resumed after five valid samples";
    for (int k = seen; k < fault_end; ++k) {
      const TickSnapshot& t = snaps[k];
      EXPECT_NE(t.device_fault, 0) << k;
      // Held: the last valid pose.
      EXPECT_EQ(t.p_WT_device, snaps[seen - 1].p_WT_device) << k;
      const double f = std::hypot(t.f_T_W[0], t.f_T_W[1], t.f_T_W[2]);
      const double f_prev =
          std::hypot(snaps[k - 1].f_T_W[0], snaps[k - 1].f_T_W[1], snaps[k - 1].f_T_W[2]);
      EXPECT_LE(f, f_prev + 1e-12) << k;
      EXPECT_GE(f, f_prev - max_step - 1e-12) << "a ramp, not a step: " << k;
      if (k >= seen + ramp_steps) {
        EXPECT_EQ(f, 0.0) << k;
      }
      EXPECT_EQ(t.period_ns, 1'000'000) << "the loop keeps its period";
    }
    // Resumed within a few samples of the end of the fault, and pushing again.
    EXPECT_EQ(snaps[kFrom + kSteps + 10].device_fault, 0);
    const TickSnapshot& after = snaps.back();
    EXPECT_GT(std::hypot(after.f_T_W[0], after.f_T_W[1], after.f_T_W[2]), 0.5);
  }
}

}  // namespace
}  // namespace microdex::station
