#pragma once
// Standard scripted trajectories of the thread, shared by tests and microdex-bench thread:
// the swing-and-pull motion of the stability and accuracy studies and the knot-tying script.

#include <Eigen/Core>
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
// hold_tension_N by feeding or taking in thread along x. Then pegs and jaws are withdrawn and
// both hands pull apart until each feels pull_tension_N. passes = 1 ties an overhand knot
// (trefoil), 2 a double overhand; right picks the handedness (all crossings positive seen from +z).
// A second throw on the same thread, next to the first, makes a square (opposite handedness) or
// granny knot; it is tied with the other end (the hands swap roles), whose tail is the long one
// after the first throw. With the driver's end towards -x of the knot the jig is turned by pi about
// the y axis.
struct KnotThrowOptions {
  int passes = 1;
  bool right = true;
  double knot_x_m = 4e-3;  // the jig's centre along the standing part
  double speed_m_per_s = 4e-3;
  double pull_speed_m_per_s = 2e-3;
  double hold_tension_N = 2e-3;
  double pull_tension_N = 10e-3;
  double max_pull_m = 8e-3;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

// The standing hand's hold for `next`, tied after `previous` on the same thread: 1 mN after a
// double throw (surgeon's knot: at 2 mN the single throw's loop sprang open when pegs and jaws
// were withdrawn and the end slipped out, 385 nodes), next.hold_tension_N otherwise (at 1 mN the
// square knot's second throw is the one lost).
double HoldTensionAfterThrow(const KnotThrowOptions& previous, const KnotThrowOptions& next);

class KnotThrowScript {
 public:
  enum class Phase { kLoop, kHelix, kExit, kPull, kDone };

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
  double sx_ = 1.0;  // +1: the driver's end lies towards +x of the knot, -1: towards -x
  Phase phase_ = Phase::kLoop;
};

}  // namespace microdex::thread
