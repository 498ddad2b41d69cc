#pragma once
// Grasping (thesis §5.4): any node can be grasped or released at run time; a grasped node
// follows its tool tip and roll, and the force the thread exerts on it is returned for the
// haptic device. None of these allocate.

#include <Eigen/Core>

#include "common/thread/thread_model.h"

namespace microdex::thread {

// Grasps node at its current position; returns the slot, or -1 when the node index is out of
// range or every slot is taken. Grasping a grasped node returns its slot.
int GraspNode(const ThreadModel& model, int node, ThreadState& state);
// Frees the slot (no-op for a free or invalid slot).
void ReleaseGrasp(ThreadState& state, int slot);
// Sets where the slot's node goes at the next step (tool tip p_WT, roll about the thread).
void SetGraspTarget(ThreadState& state, int slot, const Eigen::Vector3d& p_WT, double roll_rad);
// Force of the thread on the slot's tool after the last step, N, world frame; saturated to
// max_force_N in magnitude and always finite.
Eigen::Vector3d GraspForce(const ThreadState& state, int slot, double max_force_N);

}  // namespace microdex::thread
