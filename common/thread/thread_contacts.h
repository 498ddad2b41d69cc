#pragma once
// Contact of the thread with itself and with external objects (thesis §5.2 "contact force",
// §5.3): broad phase by the sphere hierarchy, narrow phase by exact segment distances, the
// exponential reaction law (5.9), and a non-penetration guard applied after the step.

#include <Eigen/Core>
#include <span>

#include "common/thread/colliders.h"
#include "common/thread/thread_model.h"

namespace microdex::thread {

// Refits the hierarchy on state.x_W and finds the candidate link pairs (w.pairs); returns their
// number (also in state.status.num_candidate_pairs).
int FindCandidatePairs(const ThreadModel& model, ThreadWorkspace& w, ThreadState& state);

// The link pairs at x0_W that may come into contact while every node moves by up to move_m
// (the hierarchy's spheres grown by move_m) into w.swept_pairs; returns their number (at most
// the contact capacity).
int FindSweptPairs(const ThreadModel& model, const Eigen::Matrix3Xd& x0_W, double move_m,
                   ThreadWorkspace& w);

// The candidate pairs at state.x_W and their closest points there (w.pair_start), for a
// contact projection that starts from state.x_W.
void FindPairStarts(const ThreadModel& model, ThreadWorkspace& w, ThreadState& state);

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

// Contact projection after the step (Gauss-Seidel on position constraints, one pass for all
// of them): non-adjacent links at least guard_fraction * diameter apart (centrelines; the sign
// taken along the normal at x0, so links that crossed since x0 are put back on their side),
// link surfaces at least (guard_fraction - 1) * radius from objects, and, when
// strain_limit > 0, link lengths within [1 - strain_limit, 1 + strain_limit] rest lengths
// (after each of the first 32 sweeps over the contacts, all links at once by a direct solve:
// ProjectStrainBand; the later sweeps are contacts only).
// Each contact correction carries Coulomb friction at position level: the contact points'
// relative tangential displacement since x0 is removed up to mu times the normal correction.
// Sweeps until no constraint is violated by more than 0.5 % of the diameter (at most 48).
// Uses the candidate pairs and their closest points at x0 (FindThreadContacts or
// FindPairStarts on x0). Moves state.x_W only; the caller sets the velocities.
struct ContactProjection {
  int contact_corrections = 0;
  int strain_corrections = 0;
};
ContactProjection ProjectContacts(const ThreadModel& model, std::span<const Collider> colliders,
                                  double strain_limit, const Eigen::Matrix3Xd& x0,
                                  ThreadWorkspace& w, ThreadState& state);

// The thread's load on colliders[collider], world, N, from the last FindThreadContacts (the
// step's start) and the nodes in `state`: each run of links touching the collider, extended by
// margin_links links on either side (runs whose extensions meet are one), is cut there, and the
// thread beyond pulls it with the cut links' stretch force (5.4): T_{b+1} u_{b+1} − T_{a−1}
// u_{a−1} for the extended run a..b (u along the node order; nothing beyond the thread's ends).
// A massless thread at rest whose extended run touches nothing else is in equilibrium, so this
// is what it presses on the collider, whatever carries that force: the contact law (5.9) or
// the contact projection, whose position corrections are not forces (a thread pulled deep into
// a rod sits where the law's exponential means nothing). Cut a few links away from the rod the
// links are free and straight, their stretch a clean tension. Left out: the bending shear at
// the cuts, inertia, and whatever else the extended run touches (a knot on the rod: its self
// contacts with strands outside the run).
Eigen::Vector3d CalcColliderLoad(const ThreadModel& model, const ThreadWorkspace& w,
                                 const ThreadState& state, int collider, int margin_links);

// Smallest centreline distance between non-adjacent links, over all pairs (O(n^2) reference).
double CalcMinNonAdjacentDistance(const ThreadModel& model, const Eigen::Matrix3Xd& x_W);

}  // namespace microdex::thread
