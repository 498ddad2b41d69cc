#pragma once
// Contact of the thread with itself and with external objects (thesis §5.2 "contact force",
// §5.3): broad phase by the sphere hierarchy, narrow phase by exact segment distances, the
// exponential reaction law (5.9), and a non-penetration guard applied after the step.

#include <Eigen/Core>
#include <span>

#include "common/thread/colliders.h"
#include "common/thread/thread_model.h"

namespace microdex::thread {

// Refits the hierarchy on state.x_W, finds candidate link pairs and the contacts within the
// cutoff (self and object) into the workspace's lists.
void FindThreadContacts(const ThreadModel& model, std::span<const Collider> colliders,
                        ThreadWorkspace& w, ThreadState& state);

// Magnitude of (5.9) at surface gap g: kappa_c (exp(-g / lambda) - exp(-cutoff / lambda)), 0
// beyond the cutoff; and its stiffness -df/dg.
double ContactForceMagnitude(const ThreadDef& def, double gap_m);
double ContactStiffness(const ThreadDef& def, double gap_m);

// Adds the contact forces of the found contacts to f_W; with_stiffness, also per-node 3x3
// stiffness bounds (diagonal blocks dominating the true pair stiffness) and the extra contact
// damping per node (5.8), except for the first `exact_pairs` self contacts, whose stiffness
// and damping the implicit step couples exactly (relative, per pair).
void AddContactForces(const ThreadModel& model, ThreadWorkspace& w, Eigen::Matrix3Xd& f_W,
                      bool with_stiffness, int exact_pairs = 0);

// Projects links back to at least guard_fraction * diameter apart (and out of objects), using
// the start-of-step positions in w.x_prev_W to catch links that crossed within the step.
// Velocities are corrected so that x = x_prev + h v still holds. Returns the corrections made.
int ApplyNonPenetrationGuard(const ThreadModel& model, std::span<const Collider> colliders,
                             double h, ThreadWorkspace& w, ThreadState& state);

// Smallest centreline distance between non-adjacent links, over all pairs (O(n^2) reference).
double CalcMinNonAdjacentDistance(const ThreadModel& model, const Eigen::Matrix3Xd& x_W);

}  // namespace microdex::thread
