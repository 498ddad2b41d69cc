#pragma once
// The contact solver (README.md "Solver"): projected Gauss–Seidel on the contacts' normal and
// friction impulses, warm started, with each normal row a spring and damper integrated
// implicitly (a soft constraint) and each friction row rigid inside the Coulomb disc.

#include "common/grasp/grasp_model.h"

namespace microdex::grasp {

// Stage: the sub-step's velocity without contacts: gravity, and the gyroscopic term of the
// rotation solved implicitly (one Newton step in the body frame). Writes state.v_WO, w_WO.
void ApplyFreeMotion(const GraspModel& model, double h, GraspState& state);

// Stage: solves the contacts of w for the impulses of the sub-step h and applies them to the
// object's velocity. Reads and writes w.contacts and w.warm (warm start in, impulses out);
// accumulates the step's sums (w.normal_impulse_N_s, w.f_impulse_T_W, w.tau_impulse_T_W,
// w.slip_m); writes state.v_WO, w_WO.
void SolveContacts(const GraspModel& model, double h, GraspWorkspace& w, GraspState& state);

// Stage: moves the object with its new velocity over h (symplectic Euler). Writes state.X_WO.
void IntegratePose(double h, GraspState& state);

}  // namespace microdex::grasp
