#include "common/thread/grasp.h"

namespace microdex::thread {

int GraspNode(const ThreadModel& model, int node, ThreadState& state) {
  if (node < 0 || node >= model.num_nodes) return -1;
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    if (state.grasps[slot].node == node) return slot;  // already held
  }
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    Grasp& g = state.grasps[slot];
    if (g.node >= 0) continue;
    g.node = node;
    g.p_WT = state.x_W.col(node);
    g.roll_rad = state.q_rad[node];
    g.f_T_W.setZero();
    return slot;
  }
  return -1;
}

void ReleaseGrasp(ThreadState& state, int slot) {
  if (slot < 0 || slot >= static_cast<int>(state.grasps.size())) return;
  Grasp& g = state.grasps[slot];
  g = Grasp{};
}

void SetGraspTarget(ThreadState& state, int slot, const Eigen::Vector3d& p_WT, double roll_rad) {
  if (slot < 0 || slot >= static_cast<int>(state.grasps.size())) return;
  state.grasps[slot].p_WT = p_WT;
  state.grasps[slot].roll_rad = roll_rad;
}

Eigen::Vector3d GraspForce(const ThreadState& state, int slot, double max_force_N) {
  if (slot < 0 || slot >= static_cast<int>(state.grasps.size())) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d f = state.grasps[slot].f_T_W;
  if (!f.allFinite()) return Eigen::Vector3d::Zero();
  const double norm = f.norm();
  return norm > max_force_N ? Eigen::Vector3d(f * (max_force_N / norm)) : f;
}

}  // namespace microdex::thread
