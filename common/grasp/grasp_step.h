#pragma once
// One haptic step of the grasping primitive: the forceps move to the device's pose and gripper
// value, the object meets the table and the jaws, the contact impulses are solved, the object
// moves, and the metrics and the force on the forceps are updated.

#include "common/grasp/grasp_model.h"

namespace microdex::grasp {

// Advances state by in.dt_s in model.def.solver.substeps sub-steps. Never allocates, locks or
// throws: a NaN/Inf tool pose or gripper value holds the jaws where they were, a dt outside
// (0, max_time_step_s] skips the step, a step that produces NaN/Inf puts the object back at
// rest where it was; each is counted in state.warnings. The workspace carries nothing from one
// step to the next.
void StepGrasp(const GraspModel& model, const GraspInput& in, GraspWorkspace& w, GraspState& state);

}  // namespace microdex::grasp
