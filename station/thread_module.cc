#include "station/thread_module.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>

#include "common/base/check.h"
#include "common/thread/grasp.h"
#include "common/thread/thread_step.h"

namespace microdex::station {

Eigen::Matrix3Xd CalcSlackThreadNodes(const Eigen::Vector3d& p_W_a, const Eigen::Vector3d& p_W_b,
                                      const Eigen::Vector3d& side_W, double length_m,
                                      int num_nodes) {
  MICRODEX_CHECK(num_nodes >= 2 && length_m > 0);
  Eigen::Matrix3Xd x(3, num_nodes);
  const Eigen::Vector3d chord = p_W_b - p_W_a;
  const double d = chord.norm();
  MICRODEX_CHECK(d > 0);
  const Eigen::Vector3d c = chord / d;
  // Bow direction: side_W without its part along the chord (any normal when parallel).
  Eigen::Vector3d u = side_W - side_W.dot(c) * c;
  if (u.norm() < 1e-9) u = c.unitOrthogonal();
  u.normalize();
  // Arc of length L over the chord d: half-angle θ with sin θ / θ = d / L (Newton on
  // g(θ) = sin θ − (d / L) θ from θ = π/2 ... π, where g is concave and decreasing past its
  // maximum); a taut thread (d >= L) is straight.
  const double ratio = d / length_m;
  if (ratio >= 1 - 1e-12) {
    for (int i = 0; i < num_nodes; ++i) {
      x.col(i) = p_W_a + chord * (static_cast<double>(i) / (num_nodes - 1));
    }
    return x;
  }
  double theta = std::sqrt(6 * (1 - ratio));  // small-angle start: sin θ/θ ≈ 1 − θ²/6
  theta = std::min(theta, 3.0);
  for (int it = 0; it < 60; ++it) {
    const double g = std::sin(theta) - ratio * theta;
    const double dg = std::cos(theta) - ratio;
    if (dg == 0) break;
    const double next = std::clamp(theta - g / dg, 1e-9, 3.14159);
    if (std::abs(next - theta) < 1e-15) break;
    theta = next;
  }
  const double radius_m = length_m / (2 * theta);
  // Centre below the chord's midpoint, on the side away from u.
  const Eigen::Vector3d mid = 0.5 * (p_W_a + p_W_b);
  const Eigen::Vector3d centre = mid - radius_m * std::cos(theta) * u;
  for (int i = 0; i < num_nodes; ++i) {
    const double phi = -theta + 2 * theta * static_cast<double>(i) / (num_nodes - 1);
    x.col(i) = centre + radius_m * (std::sin(phi) * c + std::cos(phi) * u);
  }
  return x;
}

double CalcAlignedRmsDistance(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& target) {
  MICRODEX_CHECK(x.cols() == target.cols() && x.cols() > 0);
  const Eigen::Vector3d cx = x.rowwise().mean();
  const Eigen::Vector3d ct = target.rowwise().mean();
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (Eigen::Index i = 0; i < x.cols(); ++i)
    H += (x.col(i) - cx) * (target.col(i) - ct).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();  // x → target
  double sq = 0;
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    sq += (R * (x.col(i) - cx) - (target.col(i) - ct)).squaredNorm();
  }
  return std::sqrt(sq / static_cast<double>(x.cols()));
}

ThreadModule::ThreadModule(const scene::SceneModel& scene)
    : second_hand_(scene.second_hand.has_value()),
      max_force_N_(scene.haptic.max_force_N),
      max_strain_(scene.thread->max_strain) {
  const scene::ThreadSceneDef& d = *scene.thread;
  if (d.def.num_nodes > static_cast<int>(kMaxFrameThreadNodes)) {
    throw std::runtime_error(scene.path + ": thread.params: " + d.params_path +
                             ": num_nodes: expected <= " + std::to_string(kMaxFrameThreadNodes) +
                             " (the ThreadState bound)");
  }
  model_ = thread::MakeThreadModel(d.def);
  ws_ = thread::MakeThreadWorkspace(model_);
  initial_ = thread::MakeThreadState(
      model_, CalcSlackThreadNodes(d.p_W_anchor, scene.CalcIdealToolPose(0).translation(),
                                   d.slack_side_W, d.def.length_m, model_.num_nodes));
  if (std::isfinite(d.floor_height_m)) {
    colliders_[0] =
        thread::Collider::Plane(Eigen::Vector3d(0, 0, d.floor_height_m), Eigen::Vector3d::UnitZ());
    num_colliders_ = 1;
  }
  anchor_slot_ = thread::GraspNode(model_, 0, initial_);
  tool_node_ = model_.num_nodes - 1;
  tool_slot_ = thread::GraspNode(model_, tool_node_, initial_);
  MICRODEX_CHECK(anchor_slot_ >= 0 && tool_slot_ >= 0);  // max_grasps >= 2 (scene validation)
  if (scene.task.kind == scene::TaskKind::kNylonLoop) {
    thread::ThreadState t = initial_;
    const double dt_s = 1.0 / scene.haptic.rate_hz;
    const auto steps = static_cast<long>(
        std::lround(scene.task.passes * scene.task.pass_duration_s * scene.haptic.rate_hz));
    const std::span<const thread::Collider> colliders(colliders_.data(), num_colliders_);
    for (long k = 0; k < steps; ++k) {
      const Eigen::Isometry3d X_WT = scene.CalcIdealToolPose(static_cast<double>(k) * dt_s);
      thread::SetGraspTarget(t, tool_slot_, X_WT.translation(), 0.0);
      thread::StepThread(model_, colliders, ws_, t);
    }
    target_W_ = t.x_W;
  }
}

void ThreadModule::InitState(state::StationState& s) const {
  s.thread = state::ThreadModuleState{initial_};
}

void ThreadModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& f_T_W) {
  state::ThreadModuleState& t = *s.thread;
  // The grasped node follows the tool tip; its torsion follows the tool's roll about x.
  const Eigen::Matrix3d& R = in.X_WT.linear();
  const double roll_rad = std::atan2(R(2, 1), R(2, 2));
  thread::SetGraspTarget(t.thread, tool_slot_, in.X_WT.translation(), roll_rad);
  if (second_hand_ && in.second_tool != nullptr) {
    const Eigen::Isometry3d& X_WT2 = in.second_tool->X_WT;
    const Eigen::Matrix3d& R2 = X_WT2.linear();
    thread::SetGraspTarget(t.thread, anchor_slot_, X_WT2.translation(),
                           std::atan2(R2(2, 1), R2(2, 2)));
  }
  thread::StepThread(model_, std::span<const thread::Collider>(colliders_.data(), num_colliders_),
                     ws_, t.thread);
  t.f_T_W = thread::GraspForce(t.thread, tool_slot_, max_force_N_);
  f_T_W += t.f_T_W;
  if (second_hand_) t.f_T2_W = thread::GraspForce(t.thread, anchor_slot_, max_force_N_);
  if (target_W_.cols() > 0) t.shape_error_m = CalcAlignedRmsDistance(t.thread.x_W, target_W_);
}

ModuleStatus ThreadModule::Status(const state::StationState& s) const {
  const thread::ThreadStatus& st = s.thread->thread.status;
  ModuleStatus out;
  out.fault = st.max_strain > max_strain_;
  out.fault_value = st.max_strain;
  out.error_estimate = st.max_strain;
  out.warnings = static_cast<std::uint32_t>(st.nonfinite_resets + st.factorization_failures +
                                            st.contact_overflows);
  return out;
}

Eigen::Vector3d ThreadModule::SecondToolForce(const state::StationState& s) const {
  return s.thread->f_T2_W;
}

void ThreadModule::WriteFrame(const state::StationState& s, std::uint64_t step,
                              std::int64_t stamp_ns, LargeFrames& frames) {
  const state::ThreadModuleState& t = *s.thread;
  ThreadFrame& f = frames.thread.back();
  f.step = step;
  f.stamp_ns = stamp_ns;
  f.num_nodes = model_.num_nodes;
  for (int i = 0; i < model_.num_nodes; ++i) {
    f.p_W[i] = {t.thread.x_W(0, i), t.thread.x_W(1, i), t.thread.x_W(2, i)};
  }
  f.max_strain = t.thread.status.max_strain;
  f.grasped_node = tool_node_;
  f.f_T_W = {t.f_T_W.x(), t.f_T_W.y(), t.f_T_W.z()};
  frames.thread.Publish();
}

}  // namespace microdex::station
