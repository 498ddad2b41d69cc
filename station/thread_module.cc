#include "station/thread_module.h"

#include <cmath>
#include <span>
#include <stdexcept>

#include "common/base/check.h"
#include "common/thread/grasp.h"
#include "common/thread/thread_step.h"

namespace microdex::station {

ThreadModule::ThreadModule(const scene::SceneModel& scene)
    : max_force_N_(scene.haptic.max_force_N), max_strain_(scene.thread->max_strain) {
  const scene::ThreadSceneDef& d = *scene.thread;
  if (d.def.num_nodes > static_cast<int>(net::kMaxThreadNodes)) {
    throw std::runtime_error(scene.path + ": thread.params: " + d.params_path +
                             ": num_nodes: expected <= " + std::to_string(net::kMaxThreadNodes) +
                             " (the ThreadState bound)");
  }
  model_ = thread::MakeThreadModel(d.def);
  state_ = thread::MakeStraightThreadState(model_, d.p_W_anchor, d.direction_W);
  if (std::isfinite(d.floor_height_m)) {
    colliders_[0] =
        thread::Collider::Plane(Eigen::Vector3d(0, 0, d.floor_height_m), Eigen::Vector3d::UnitZ());
    num_colliders_ = 1;
  }
  anchor_slot_ = thread::GraspNode(model_, 0, state_);
  tool_node_ = model_.num_nodes - 1;
  tool_slot_ = thread::GraspNode(model_, tool_node_, state_);
  MICRODEX_CHECK(anchor_slot_ >= 0 && tool_slot_ >= 0);  // max_grasps >= 2 (scene validation)
}

void ThreadModule::Step(const ToolInput& in, Eigen::Vector3d& f_T_W) {
  // The grasped node follows the tool tip; its torsion follows the tool's roll about x.
  const Eigen::Matrix3d& R = in.X_WT.linear();
  const double roll_rad = std::atan2(R(2, 1), R(2, 2));
  thread::SetGraspTarget(state_, tool_slot_, in.X_WT.translation(), roll_rad);
  thread::StepThread(model_, std::span<const thread::Collider>(colliders_.data(), num_colliders_),
                     state_);
  f_tool_W_ = thread::GraspForce(state_, tool_slot_, max_force_N_);
  f_T_W += f_tool_W_;
}

std::uint32_t ThreadModule::warnings() const {
  const thread::ThreadStatus& s = state_.status;
  return static_cast<std::uint32_t>(s.nonfinite_resets + s.factorization_failures +
                                    s.contact_overflows);
}

void ThreadModule::WriteSnapshot(TickSnapshot& /*snapshot*/) const {}

void ThreadModule::WriteFrame(std::uint64_t step, std::int64_t stamp_ns, LargeFrames& frames) {
  ThreadFrame& f = frames.thread.back();
  f.step = step;
  f.stamp_ns = stamp_ns;
  f.num_nodes = model_.num_nodes;
  for (int i = 0; i < model_.num_nodes; ++i) {
    f.p_W[i] = {state_.x_W(0, i), state_.x_W(1, i), state_.x_W(2, i)};
  }
  f.max_strain = state_.status.max_strain;
  f.grasped_node = tool_node_;
  f.f_grasp_W = {f_tool_W_.x(), f_tool_W_.y(), f_tool_W_.z()};
  frames.thread.Publish();
}

}  // namespace microdex::station
