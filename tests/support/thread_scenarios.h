#pragma once
// Standard scripted trajectories of the thread, shared by tests and microdex-bench thread:
// the swing-and-pull motion of the stability and accuracy studies and the knot-tying script.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/thread/colliders.h"
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

// The two hands of a bimanual tie: the standing hand holds the standing end (node 0), the
// driver (the needle holder) holds the working end (last node).
struct KnotTyingHands {
  int standing_slot = -1;
  int driver_slot = -1;
};

// Lays the thread straight along +x from the origin and grasps both ends.
KnotTyingHands SetUpKnotTying(const ThreadModel& model, ThreadState& state);

// One throw, tied as by hand on a jig (thesis §5.5, Fig. 5.7): the driver carries the working
// end under a first peg, over it and a second peg (the loop), back across the standing part
// and `passes` times around the standing part inside the loop (a helix), then away to +x.
// The helix is wrapped on an instrument's jaws: two rigid rods along the standing part, one on
// either side of it, which keep the standing part (held only by thread tension) inside the
// wraps, as in an instrument tie. Meanwhile the standing hand keeps the thread taut at
// hold_tension_N by feeding or taking in thread along x. Then pegs and jaws shrink to nothing
// over 0.1 s (release: the instrument opens) and both hands pull apart until each feels
// pull_tension_N. passes = 1 ties an overhand knot (trefoil), 2 a double overhand; right picks the
// handedness (all crossings positive seen from +z). A second throw on the same thread, next to the
// first, makes a square (opposite handedness) or granny knot; it is tied with the other end (the
// hands swap roles), whose tail is the long one after the first throw. With the driver's end
// towards -x of the knot the jig is turned by pi about the y axis.
struct KnotThrowOptions {
  int passes = 1;
  bool right = true;
  double knot_x_m = 4e-3;  // the jig's centre along the standing part
  double speed_m_per_s = 4e-3;
  double pull_speed_m_per_s = 2e-3;
  double hold_tension_N = 2e-3;
  double pull_tension_N = 10e-3;
  double max_pull_m = 8e-3;
  // Colliders present throughout and never withdrawn with the jig (a stitch).
  std::vector<Collider> fixed_colliders;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

class KnotThrowScript {
 public:
  enum class Phase { kLoop, kHelix, kExit, kRelease, kPull, kDone };

  // The jig is placed on the standing part as it lies in `state` (it need not be straight
  // after an earlier throw). Precomputes the driver's path; allocates only here.
  KnotThrowScript(const ThreadModel& model, const ThreadState& state, KnotTyingHands hands,
                  const KnotThrowOptions& options);

  // Moves the hands by one time step of model.def.time_step_s and steps the thread. Returns
  // false when the throw is over.
  bool Step(const ThreadModel& model, ThreadState& state);
  Phase phase() const { return phase_; }
  bool done() const { return phase_ == Phase::kDone; }
  const std::vector<Collider>& colliders() const { return colliders_; }
  const ThreadWorkspace& workspace() const { return ws_; }
  // Driver path length left before the pull, m.
  double path_left_m() const { return path_total_m_ - path_s_m_; }

 private:
  struct Waypoint {
    Eigen::Vector3d p_W;
    Phase phase;
  };
  KnotThrowOptions options_;
  KnotTyingHands hands_;
  ThreadWorkspace ws_;
  std::vector<Collider> colliders_;
  std::vector<Waypoint> path_;
  int segment_ = 0;
  double path_s_m_ = 0.0;
  double path_total_m_ = 0.0;
  double segment_s_m_ = 0.0;
  double pulled_m_ = 0.0;
  double released_s_ = 0.0;
  std::vector<double> radii_;  // of the colliders, before the release
  double sx_ = 1.0;            // +1: the driver's end lies towards +x of the knot, -1: towards -x
  Phase phase_ = Phase::kLoop;
  std::size_t num_jig_ = 0;  // colliders_[0, num_jig_): pegs and jaws; then the fixed ones
};

// ---- Hold ------------------------------------------------------------------------------------
// After the pull: each hand keeps tension_N along the thread for duration_s (it moves away from
// the other hand when the pull is below that and towards it when above, as the standing hand
// of a throw does).
struct KnotHoldOptions {
  double tension_N = 20e-3;
  double duration_s = 2.0;
  std::vector<Collider> fixed_colliders;  // e.g. the stitch
};

class KnotHoldScript {
 public:
  KnotHoldScript(const ThreadModel& model, KnotTyingHands hands, const KnotHoldOptions& options);
  // One step of model.def.time_step_s; false when the hold is over.
  bool Step(const ThreadModel& model, ThreadState& state);
  const ThreadWorkspace& workspace() const { return ws_; }

 private:
  KnotHoldOptions options_;
  KnotTyingHands hands_;
  ThreadWorkspace ws_;
  int steps_left_ = 0;
};

// ---- Tie and hold, measured -------------------------------------------------------------------
// Throws of a knot as "2" (double overhand), "1r" (overhand), "1r,1l" (square), "1r,1r"
// (granny), "2r,1l" (surgeon's): passes and r/l handedness per throw. Throws
// std::invalid_argument naming the bad item.
std::vector<KnotThrowOptions> ParseKnotThrows(const std::string& spec);

// A stitch for the knot-tying jig (the thread module's picture of a bite through tissue, in the
// jig's frame: the thread along +x at y = 0, y up): the thread runs flat from the standing end
// at start_x_m to a guide rod under it (the first puncture), down under a deep rod (the bite),
// up over a second guide rod (the second puncture) and flat again to its other end. All rods
// are capsules along z, frictionless. The first throw's jig (at x = 4 mm) lies on the standing
// part before the first guide, so the stitch is inside the throw's loop: the knot is tied
// around it and slides onto the first puncture when pulled.
struct KnotStitchDef {
  double x_m = 9e-3;               // the bite's centre
  double depth_m = 1e-3;           // the bite rod's centre below the thread's line
  double guide_offset_m = 2.5e-3;  // guides at x_m -+ this
  double rod_radius_m = 0.15e-3;
  double guide_radius_m = 0.1e-3;
  double start_x_m = -2e-3;  // the standing end
  // The rods, for a thread of this radius (the guides' tops at y = 0 under its centreline).
  std::vector<Collider> Colliders(double thread_radius_m) const;
  // The thread laid along the stitch's path from start_x_m.
  ThreadState Lay(const ThreadModel& model) const;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

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
  int max_projection_sweeps = 0;  // contact projection (ProjectContacts)
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

// Ties the throws on a fresh thread of `def` (laid out and grasped by SetUpKnotTying; a second
// throw is tied by the other hand 3 mm beyond the knot), each with its script's hold and pull
// tensions, then holds (`hold`). Times every step; after every step the brute-force distance.
// The knot is recognised at every phase change. on_phase, when given, is called after each
// phase with its report (progress output).
// With `stitch`, the thread is laid through it (KnotStitchDef) and its rods stay for every
// throw and the hold.
TieReport RunKnotTie(const ThreadDef& def, std::vector<KnotThrowOptions> throws,
                     KnotHoldOptions hold, void (*on_phase)(const TiePhaseReport&) = nullptr,
                     const KnotStitchDef* stitch = nullptr);

}  // namespace microdex::thread
