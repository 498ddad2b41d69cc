// The torque sent to the device: the needle's wall contact pushes at the deepest needle point,
// so the tool feels (p_WD - p_WT) x f about its point. Checked against the wall's energy
// E = k c^2 / 2 (c < 0: the depth outside the tube): force and torque are minus its gradient
// under translations and rotations of the tool about its point (central differences of the
// analytic clearance). The torque is saturated at haptic.max_torque_Nm, ramped to zero with
// the force during a device fault, and the workspace mapping rotates it into the device frame.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/geometry/arc_torus_sp.h"
#include "station/device_mapping.h"
#include "station/station_step.h"

namespace microdex::station {
namespace {

scene::SceneModel NeedleScene(double max_torque_Nm) {
  return scene::ParseScene(R"(
name: torque-needle
modules: [needle]
vessel: {core_radius_m: 5.0e-3, tube_radius_m: 0.5e-3, segment_angle_rad: 4.71238898}
needle: {radius_m: 5.0e-3, sweep_rad: 1.04719755}
task: {pass_duration_s: 2.0, start_azimuth_rad: 0.2, end_azimuth_rad: 3.3}
haptic: {rate_hz: 1000, max_force_N: 1.0, max_torque_Nm: )" +
                               std::to_string(max_torque_Nm) +
                               R"(, wall_stiffness_N_per_m: 1000}
)",
                           "inline");
}

// The tool 0.2 mm (and a little turned) outside the tube at 0.6 s into the ideal pass.
Eigen::Isometry3d PoseInTheWall(const scene::SceneModel& scene) {
  Eigen::Isometry3d X = scene.CalcIdealToolPose(0.6);
  X.translation() += Eigen::Vector3d(0.1e-3, -0.2e-3, 0.65e-3);
  X.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, 2, 0.5).normalized()) * X.linear();
  return X;
}

// The wall's energy for the tool at X (zero inside the tube).
double WallEnergy(const scene::SceneModel& scene, double k, const Eigen::Isometry3d& X) {
  geometry::ArcDef arc = scene.needle;
  arc.X_WN = X * scene.X_TN();
  const geometry::ArcTorusClearance c = geometry::CalcArcTorusClearanceSP(arc, scene.vessel);
  EXPECT_EQ(c.status, geometry::ClearanceStatus::kOk);
  return c.clearance_m < 0 ? 0.5 * k * c.clearance_m * c.clearance_m : 0.0;
}

state::StationState StepAt(Simulation& sim, const Eigen::Isometry3d& X, int steps,
                           DeviceFault fault = DeviceFault::kNone,
                           state::StationState* from = nullptr) {
  state::StationState s = from != nullptr ? *from : sim.MakeInitialState(1);
  StationInput in;
  in.device.X_WT = X;
  in.device.fault = fault;
  for (int k = 0; k < steps; ++k) StepStation(sim, in, s);
  return s;
}

TEST(ToolTorque, NeedleWallTorqueIsMinusTheEnergyGradientUnderRotation) {
  const scene::SceneModel scene = NeedleScene(0.05);
  Simulation sim(scene);
  const Eigen::Isometry3d X = PoseInTheWall(scene);
  const state::StationState s = StepAt(sim, X, 1);
  ASSERT_TRUE(s.needle->clearance.clearance_m < -0.05e-3) << s.needle->clearance.clearance_m;
  const double k = scene.haptic.wall_stiffness_N_per_m * s.cues.p(cues::CueKind::kWall);
  ASSERT_GT(k, 0);
  // Minus the gradient by central differences: translations for the force, rotations about
  // the tool point (world axes) for the torque.
  constexpr double kH_m = 1e-8, kH_rad = 1e-7;
  Eigen::Vector3d f_fd, tau_fd;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(i);
    Eigen::Isometry3d Xp = X, Xm = X;
    Xp.translation() += kH_m * e;
    Xm.translation() -= kH_m * e;
    f_fd[i] = -(WallEnergy(scene, k, Xp) - WallEnergy(scene, k, Xm)) / (2 * kH_m);
    Xp = X, Xm = X;
    Xp.linear() = Eigen::AngleAxisd(kH_rad, e) * X.linear();
    Xm.linear() = Eigen::AngleAxisd(-kH_rad, e) * X.linear();
    tau_fd[i] = -(WallEnergy(scene, k, Xp) - WallEnergy(scene, k, Xm)) / (2 * kH_rad);
  }
  const Eigen::Vector3d f = s.tool.f_T_W, tau = s.tool.tau_T_W;
  ASSERT_GT(tau.norm(), 1e-5) << "a lever of millimetres and a force of a tenth of a newton";
  EXPECT_LT((f - f_fd).norm(), 1e-3 * f_fd.norm()) << f.transpose() << " vs " << f_fd.transpose();
  EXPECT_LT((tau - tau_fd).norm(), 1e-3 * tau_fd.norm())
      << tau.transpose() << " vs " << tau_fd.transpose();
  // And it is the lever times the force, the lever from the tool point to the needle point D.
  const Eigen::Vector3d lever = s.needle->clearance.p_WD - X.translation();
  EXPECT_LT((tau - lever.cross(f)).norm(), 1e-12);
  // Inside the tube: no torque.
  const state::StationState inside = StepAt(sim, scene.CalcIdealToolPose(0.6), 1);
  EXPECT_EQ(inside.tool.tau_T_W, Eigen::Vector3d::Zero());
}

TEST(ToolTorque, SaturatedAndRampedToZeroDuringADeviceFault) {
  constexpr double kMax_Nm = 2e-5;
  const scene::SceneModel scene = NeedleScene(kMax_Nm);
  Simulation sim(scene);
  const Eigen::Isometry3d X = PoseInTheWall(scene);
  state::StationState s = StepAt(sim, X, 5);
  EXPECT_NEAR(s.tool.tau_T_W.norm(), kMax_Nm, 1e-15) << "saturated";
  // A fault: the torque goes to zero at max_torque / max_force times the force's rate.
  const double step_Nm = cues::kMaxForceRate_N_per_s * scene.haptic.max_torque_Nm /
                         scene.haptic.max_force_N * sim.dt_s();
  const int ramp = static_cast<int>(std::ceil(kMax_Nm / step_Nm));
  double prev = s.tool.tau_T_W.norm();
  for (int k = 0; k < ramp + 2; ++k) {
    s = StepAt(sim, X, 1, DeviceFault::kTimeout, &s);
    const double now = s.tool.tau_T_W.norm();
    EXPECT_LE(now, prev + 1e-18) << k;
    EXPECT_GE(now, prev - step_Nm * (1 + 1e-9)) << "a ramp, not a step: " << k;
    prev = now;
  }
  EXPECT_EQ(s.tool.tau_T_W, Eigen::Vector3d::Zero());
  EXPECT_EQ(s.tool.f_T_W, Eigen::Vector3d::Zero());
}

TEST(ToolTorque, MappingRotatesScalesAndLimitsIt) {
  DeviceMappingDef def;
  def.R_WD = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  def.torque_scale = 2.0;
  def.max_torque_Nm = 0.1;
  const DeviceMapping m(def);
  // A torque about world y is about the device's x (device x = world y).
  EXPECT_TRUE(
      m.TorqueToDevice(Eigen::Vector3d(0, 0.01, 0)).isApprox(Eigen::Vector3d(0.02, 0, 0), 1e-12));
  EXPECT_NEAR(m.TorqueToDevice(Eigen::Vector3d(0, 0, 5)).norm(), 0.1, 1e-12);
  EXPECT_EQ(m.TorqueToDevice(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0)),
            Eigen::Vector3d::Zero());
  DeviceMappingDef no_torque;
  no_torque.max_torque_Nm = 0;  // a 3-DOF device
  EXPECT_EQ(DeviceMapping(no_torque).TorqueToDevice(Eigen::Vector3d(0.01, 0, 0)),
            Eigen::Vector3d::Zero());
  DeviceMappingDef bad;
  bad.max_torque_Nm = -1;
  EXPECT_THROW(DeviceMapping{bad}, std::invalid_argument);
  try {
    NeedleScene(0);
    ADD_FAILURE() << "a zero torque limit was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("haptic.max_torque_Nm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace microdex::station
