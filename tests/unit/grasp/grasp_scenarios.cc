#include "tests/unit/grasp/grasp_scenarios.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "common/grasp/grasp_contacts.h"
#include "common/grasp/grasp_step.h"

namespace microdex::grasp::testing {
namespace {

// Smooth 0 -> 1 over [0, 1] with zero velocity at both ends.
double Smooth(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return 0.5 * (1.0 - std::cos(std::numbers::pi * s));
}

double Yaw(const Eigen::Quaterniond& q, int axis) {
  const Eigen::AngleAxisd aa(q);
  return aa.angle() * aa.axis()[axis];
}

}  // namespace

GraspDef MilligramCubeDef(double jaw_friction) {
  GraspDef def;
  def.shape.kind = ShapeKind::kBox;
  def.shape.box_size_m = Eigen::Vector3d(1e-3, 1e-3, 1e-3);
  def.density_kg_per_m3 = 1000.0;
  def.jaw_friction = jaw_friction;
  def.table_friction = 0.5;
  def.jaws.width_m = 0.8e-3;
  def.jaws.length_m = 0.8e-3;
  def.jaws.thickness_m = 0.3e-3;
  def.jaws.open_gap_m = 2e-3;
  def.jaws.closed_gap_m = -1e-3;
  def.contact.jaw_stiffness_N_per_m = 1.0;
  return def;
}

GraspInput FarTool(double dt_s) {
  GraspInput in;
  in.X_WT.translation() = Eigen::Vector3d(1.0, 1.0, 1.0);
  in.gripper = 0.0;
  in.dt_s = dt_s;
  return in;
}

InclineResult RunIncline(GraspDef def, double theta_rad, double t0_s, double t1_s) {
  const double g = def.gravity_m_per_s2.norm();
  def.gravity_m_per_s2 = g * Eigen::Vector3d(std::sin(theta_rad), 0.0, -std::cos(theta_rad));
  const GraspModel model = MakeGraspModel(def);
  GraspState state = MakeGraspStateOnTable(model, Eigen::Vector3d::Zero());
  GraspWorkspace w;
  const GraspInput in = FarTool();
  double x0 = state.X_WO.p_W.x();
  double v0 = 0.0;
  const int n0 = static_cast<int>(std::lround(t0_s / in.dt_s));
  const int n1 = static_cast<int>(std::lround(t1_s / in.dt_s));
  InclineResult r;
  for (int k = 1; k <= n1; ++k) {
    StepGrasp(model, in, w, state);
    if (k == n0) {
      v0 = state.v_WO.x();
      x0 = state.X_WO.p_W.x();
    }
  }
  r.acceleration_m_per_s2 = (state.v_WO.x() - v0) / (t1_s - t0_s);
  r.displacement_m = state.X_WO.p_W.x() - x0;
  r.finite = state.X_WO.p_W.allFinite() && state.v_WO.allFinite();
  return r;
}

LiftResult RunLift(const GraspDef& def, double width_m, const LiftOptions& o,
                   std::vector<double>* step_us) {
  const GraspModel model = MakeGraspModel(def);
  GraspState state = MakeGraspStateOnTable(model, Eigen::Vector3d::Zero());
  GraspWorkspace w;
  const double z0 = state.X_WO.p_W.z();
  const double gap = width_m - 2.0 * o.squeeze_m;
  const JawDef& jaws = def.jaws;
  const double g_closed = (jaws.open_gap_m - gap) / (jaws.open_gap_m - jaws.closed_gap_m);
  GraspInput in;
  in.dt_s = o.dt_s;
  in.X_WT.linear() = Eigen::AngleAxisd(o.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d p0_WT(o.offset_x_m, 0.0, z0);
  LiftResult r;
  const double t_close = o.close_s, t_settle = t_close + o.settle_s;
  const double t_lift = t_settle + o.lift_s, t_end = t_lift + o.hold_s;
  const int steps = static_cast<int>(std::lround(t_end / o.dt_s));
  for (int k = 1; k <= steps; ++k) {
    const double t = k * o.dt_s;
    in.gripper = g_closed * Smooth(t / t_close);
    const double rise = o.lift_m * Smooth((t - t_settle) / o.lift_s);
    in.X_WT.translation() = p0_WT + Eigen::Vector3d(0.0, 0.0, rise);
    const auto t0 = std::chrono::steady_clock::now();
    StepGrasp(model, in, w, state);
    if (step_us != nullptr) {
      step_us->push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    }
    if (k == static_cast<int>(std::lround(t_settle / o.dt_s))) {
      r.grip_force_N = state.metrics.grip_force_N;
    }
  }
  r.rise_m = state.X_WO.p_W.z() - z0;
  r.lifted = r.rise_m > 0.5 * o.lift_m && state.metrics.lifted;
  r.rotation_y_rad = Yaw(state.X_WO.q(), 1);
  r.yaw_rad = Yaw(state.X_WO.q(), 2);
  r.final = state;
  return r;
}

HoldThreshold FindHoldThreshold(const GraspDef& def, double width_m, int bisections) {
  // Bracket: no squeeze drops it; the squeeze whose spring force alone is 10x the weight
  // (the jaw stiffness is shared among the face's contact points, so this is generous).
  const double weight = MakeGraspModel(def).weight_N;
  double lo = 0.0;
  double hi = 10.0 * weight / def.contact.jaw_stiffness_N_per_m;
  LiftOptions o;
  HoldThreshold t;
  o.squeeze_m = hi;
  LiftResult r = RunLift(def, width_m, o);
  t.held_grip_N = r.grip_force_N;
  t.dropped_grip_N = 0.0;
  for (int i = 0; i < bisections; ++i) {
    o.squeeze_m = 0.5 * (lo + hi);
    r = RunLift(def, width_m, o);
    if (r.lifted) {
      hi = o.squeeze_m;
      t.held_grip_N = r.grip_force_N;
    } else {
      lo = o.squeeze_m;
      t.dropped_grip_N = r.grip_force_N;
    }
  }
  return t;
}

}  // namespace microdex::grasp::testing
