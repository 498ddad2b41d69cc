#pragma once
// The trainer's metrics of a grasp (README.md "Metrics"), updated once per step.

#include "common/grasp/grasp_model.h"

namespace microdex::grasp {

// Angle between the jaws' closing direction (y_T in world) and the object's nearest face
// normal (box), its axis or cross-section plane, whichever is nearer (cylinder), 0 (sphere).
double CalcAlignmentAngle(const GraspModel& model, const Eigen::Quaterniond& q_WO,
                          const Eigen::Vector3d& closing_W);
// Distance from the object's centre of mass to the closing line (through the tool origin
// along the closing direction).
double CalcClosingOffset(const Eigen::Vector3d& p_WO, const Eigen::Vector3d& p_WT,
                         const Eigen::Vector3d& closing_W);
// Rotation angle between two orientations, in [0, pi].
double CalcRotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

// Stage: reads the step's outputs (state.out), the tool (state.X_WT, the new one), the slip
// of the step (w.slip_m) and the object's pose at its start (w.X_WO_start); writes
// state.metrics.
void UpdateMetrics(const GraspModel& model, double dt, const GraspWorkspace& w, GraspState& state);

}  // namespace microdex::grasp
