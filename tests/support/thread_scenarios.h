#pragma once
// Standard scripted trajectories of the thread, shared by tests and microdex-bench thread:
// the swing-and-pull motion of the stability and accuracy studies and the knot-tying script.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/thread/colliders.h"
#include "common/thread/knot_tie.h"
#include "common/thread/thread_model.h"

namespace microdex::thread {

// ---- Swing and pull ------------------------------------------------------------------------
// A 33-node, 50 mm thread, node 0 held fixed, node 32 grasped: dropped over a rod, swung
// around over the top and down the far side, then pulled nearly straight, in 2 s.
ThreadDef SwingPullDef(double stretch_N_per_m, double bend_N_m, double node_mass_kg);

struct SwingPullOptions {
  Integrator integrator = Integrator::kLinearlyImplicitEuler;
  double time_step_s = 1e-3;
  double duration_s = 2.0;
  double sample_period_s = 0.02;  // node positions are recorded this often
  bool stop_when_unstable = true;
  // The rod the thread is dropped over. Without it the motion is free of contact events
  // (the accuracy study needs a smooth reference trajectory).
  bool rod = true;
};

struct SwingPullReport {
  bool finite = true;  // no NaN/Inf and no rolled-back step
  bool energy_bounded = true;
  bool strain_ok = true;      // max link strain < 10 %
  bool no_tunnelling = true;  // no link through the rod, no non-adjacent links < 0.5 d apart
  bool stable() const { return finite && energy_bounded && strain_ok && no_tunnelling; }
  double max_strain = 0.0;
  double max_energy_J = 0.0;
  double energy_bound_J = 0.0;
  int steps = 0;
  double seconds_per_step = 0.0;  // median-free mean wall time, filled by the caller if wanted
  int max_self_contacts = 0;      // most self contacts in one step
  int max_object_contacts = 0;
  std::vector<Eigen::Matrix3Xd> samples;  // positions every sample_period_s
};

SwingPullReport RunSwingPull(const ThreadDef& def, const SwingPullOptions& options);

// ---- Knot tying ----------------------------------------------------------------------------
// The thread for the knot tests and benchmarks: stiff nylon 10-0 without gravity (the suture
// floats in fluid), num_nodes nodes, links of two diameters (fine enough to resolve a knot
// pulled tight) but never shorter than needed for a 12.8 mm thread, so that every size of the
// benchmark carries the same knot-tying trajectory.
ThreadDef KnotTyingDef(int num_nodes);

// A 65-node thread (model.num_nodes == 65) laid along +x from the origin and folded into a U
// (its second half back along the first, 30 um beside it), so that it has self contacts, over
// a capsule across it just below (object contacts): the colliders.
std::vector<Collider> FoldIntoUOverACapsule(const ThreadModel& model, ThreadState& state);

// Lays the thread straight along +x from the origin and grasps both ends.
KnotTyingHands SetUpKnotTying(const ThreadModel& model, ThreadState& state);

// Smallest centreline distance between non-adjacent links of the polyline x (3 x n), over the
// pairs closer than limit_m (limit_m if none is): a brute force over all pairs, pruned only by
// each pair's bounding spheres, independent of the simulation's hierarchy.
double BruteForceMinDistance(const Eigen::Matrix3Xd& x, double limit_m);

struct TiePhaseReport {
  int throw_index = 0;  // 1-based; 0 for the hold
  std::string phase;    // loop, helix, exit, pull, hold
  std::string knot;     // recognised at the end of the phase
  int steps = 0;
  double min_distance_over_d = 0.0;  // over every step of the phase, brute force
  double steps_per_s = 0.0;          // 1 / median step time
  double tick_p99_us = 0.0;          // 99th percentile step time
  int max_self_contacts = 0;
  int max_projection_sweeps = 0;     // contact projection (ProjectContacts), in one part
  double pair_tests_per_step = 0.0;  // its link-pair distance tests, mean over the phase
  // Its parts per step and sweeps per step (summed over the parts), means over the phase.
  double projection_parts_per_step = 0.0;
  double projection_sweeps_per_step = 0.0;
  double max_projection_residual_over_d = 0.0;
  double f_standing_max_N = 0.0;
  double f_driver_max_N = 0.0;
};

struct TieReport {
  std::vector<TiePhaseReport> phases;
  std::string knot_after_pull;  // at the end of the last throw's pull
  std::string knot;             // at the end (after the hold)
  double min_distance_over_d = 0.0;
  bool pulled_tight = false;  // every throw's pull ended with both hands at pull_tension_N
  bool held = false;          // class unchanged by the hold and knot moved < 1 mm along it
  double hold_shift_m = 0.0;  // knot core's shift along the thread during the hold
  double steps_per_s = 0.0;   // 1 / median step time over the whole run
  double tick_p99_us = 0.0;
  long long rollbacks = 0;
  double max_strain = 0.0;       // largest link strain up to the end of the last pull
  double max_strain_hold = 0.0;  // the same during the hold
  Eigen::Matrix3Xd x_final_W;    // node positions at the end
};

// The second throw's exit of a two-throw tie (nullptr for one throw), and the capstan bound on
// the driver's pull there: drawing the end out past the first knot, contact friction can make
// the driver's pull at most exp(mu theta) times the standing hand's, theta the throw's wrap of
// thread on thread (1.5 turns, 3 pi). An anchoring contact model drags the whole knot and
// exceeds it several times over. (A single throw's exit draws the thread round the jig's pegs
// and jaws as well, which the estimate does not cover.)
const TiePhaseReport* SecondThrowExit(const TieReport& r);
double CapstanBound_N(const TiePhaseReport& exit, double friction);

// The tension each throw of the tie matrix is pulled to (`microdex-bench thread --tie-matrix`,
// `--tie`, and the matrix's cases in thread_knot_tying_test) before the 20 mN hold: the same
// for every knot, node count and friction. At 10 mN (the scripts' default) a double overhand's
// core was still loose after the pull at 385 nodes, μ 0.3, and drew together in the hold
// (its centre moved 1.05 mm); at 20 mN a surgeon's knot lost its single throw in the pull (257
// nodes, μ 0.2); at 15 mN all 60 cases tie and hold (common/thread/README.md, "Tie and hold").
inline constexpr double kTieMatrixPullTension_N = 15e-3;

// Ties the throws on a fresh thread of `def` (laid out and grasped by SetUpKnotTying; a second
// throw is tied by the other hand 3 mm beyond the knot), each with its script's hold and pull
// tensions, then holds (`hold`). Times every step; after every step the brute-force distance.
// The knot is recognised at every phase change. on_phase, when given, is called after each
// phase with its report (progress output).
// With `stitch`, the thread is laid through it (KnotStitchDef) and its rods stay for every
// throw and the hold. next_offset_m: how far beyond the knot the next throw's jig is placed.
TieReport RunKnotTie(const ThreadDef& def, std::vector<KnotThrowOptions> throws,
                     KnotHoldOptions hold, void (*on_phase)(const TiePhaseReport&) = nullptr,
                     const KnotStitchDef* stitch = nullptr, double next_offset_m = 3e-3);

}  // namespace microdex::thread
