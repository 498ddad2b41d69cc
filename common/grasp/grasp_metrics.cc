#include "common/grasp/grasp_metrics.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace microdex::grasp {

double CalcAlignmentAngle(const GraspModel& model, const Eigen::Quaterniond& q_WO,
                          const Eigen::Vector3d& closing_W) {
  const Eigen::Matrix3d R_WO = q_WO.toRotationMatrix();
  const Eigen::Vector3d d = closing_W.normalized();
  auto angle_to_axis = [&](int i) {
    return std::acos(std::clamp(std::abs(d.dot(R_WO.col(i))), 0.0, 1.0));
  };
  switch (model.shape.kind) {
    case ShapeKind::kBox:
      return std::min({angle_to_axis(0), angle_to_axis(1), angle_to_axis(2)});
    case ShapeKind::kCylinder: {
      const double to_axis = angle_to_axis(2);
      return std::min(to_axis, 0.5 * std::numbers::pi - to_axis);
    }
    case ShapeKind::kSphere:
      return 0.0;
  }
  return 0.0;
}

double CalcClosingOffset(const Eigen::Vector3d& p_WO, const Eigen::Vector3d& p_WT,
                         const Eigen::Vector3d& closing_W) {
  const Eigen::Vector3d d = closing_W.normalized();
  const Eigen::Vector3d r = p_WO - p_WT;
  return (r - r.dot(d) * d).norm();
}

double CalcRotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const double c = std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0);
  return 2.0 * std::acos(c);
}

void UpdateMetrics(const GraspModel& model, double dt, const GraspWorkspace& w, GraspState& state) {
  GraspMetrics& m = state.metrics;
  const double threshold_N = model.def.metrics.grip_weight_fraction * model.weight_N;
  const double f_plus = state.out.normal_force_N[kJawPlusPair];
  const double f_minus = state.out.normal_force_N[kJawMinusPair];
  const bool touching = f_plus > threshold_N || f_minus > threshold_N;
  const bool held = f_plus > threshold_N && f_minus > threshold_N;
  const bool on_table = state.out.normal_force_N[kTablePair] > threshold_N;

  // A grasp starts at the jaws' first touch and ends release_time_s after their last.
  if (touching) {
    if (!m.grasping) {
      m.grasping = true;
      ++m.grasps;
      // The object as the jaws found it: at the start of the step in which they touched.
      m.touch_pose = w.X_WO_start;
      const Eigen::Quaterniond q_WT(state.X_WT.q());
      const Eigen::Vector3d closing_W = q_WT * Eigen::Vector3d::UnitY();
      m.alignment_angle_rad = CalcAlignmentAngle(model, m.touch_pose.q(), closing_W);
      m.closing_offset_m = CalcClosingOffset(m.touch_pose.p_W, state.X_WT.p_W, closing_W);
    }
    m.time_since_jaw_contact_s = 0.0;
  } else if (m.grasping) {
    m.time_since_jaw_contact_s += dt;
    if (m.time_since_jaw_contact_s > model.def.metrics.release_time_s) m.grasping = false;
  }
  if (m.grasping) {
    m.induced_rotation_rad = CalcRotationAngle(m.touch_pose.q(), state.X_WO.q());
    m.max_induced_rotation_rad = std::max(m.max_induced_rotation_rad, m.induced_rotation_rad);
  }

  m.grip_force_N = 0.5 * (f_plus + f_minus);
  m.peak_grip_force_N = std::max(m.peak_grip_force_N, m.grip_force_N);
  if (held) {
    m.held_time_s += dt;
    m.grip_impulse_held_N_s += m.grip_force_N * dt;
    m.slip_distance_m += w.slip_m;
  }
  // Lifted: held off the table. A drop: the jaws lose a lifted object in the air.
  const bool lifted = held && !on_table;
  if (lifted && !m.lifted) ++m.lifts;
  if (m.lifted && !held && !on_table) ++m.drops;
  m.held = held;
  m.lifted = lifted;
}

}  // namespace microdex::grasp
