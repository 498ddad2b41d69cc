#pragma once
// One time step of the thread (thesis §5.4 algorithm flow): read the grasped control nodes,
// find contacts, compute the forces (5.3), integrate, keep links apart, check the result.

#include <span>

#include "common/thread/colliders.h"
#include "common/thread/thread_model.h"

namespace microdex::thread {

// Advances state by model.def.time_step_s with model.def.integrator. Reads the grasp targets
// and the colliders' current poses; writes positions, velocities, torsion, the grasp forces and
// the status; uses the workspace (MakeThreadWorkspace) for everything else. Never allocates or
// throws: a step that fails (NaN/Inf, non-SPD system) is rolled back to the previous positions
// at rest and counted in state.status.
void StepThread(const ThreadModel& model, std::span<const Collider> colliders, ThreadWorkspace& w,
                ThreadState& state);

// The same, with the integrator and time step given explicitly (for studies).
void StepThreadWith(const ThreadModel& model, Integrator integrator, double h,
                    std::span<const Collider> colliders, ThreadWorkspace& w, ThreadState& state);

}  // namespace microdex::thread
