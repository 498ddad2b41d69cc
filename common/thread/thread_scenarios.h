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
  std::vector<Eigen::Matrix3Xd> samples;  // positions every sample_period_s
};

SwingPullReport RunSwingPull(const ThreadDef& def, const SwingPullOptions& options);

// ---- Knot tying ----------------------------------------------------------------------------
// A knot-tying jig: four vertical pegs hold a loop open while the working end (grasp A) winds
// around them, crosses the standing part, passes through the loop `passes` times (1: overhand,
// 2: double overhand), then the pegs are removed and both grasps pull the knot tight. The
// standing end (grasp B) stays put until the pull. mirror flips the handedness (z -> -z).
struct KnotTieOptions {
  int passes = 1;
  bool mirror = false;
  // Where along x the jig sits, as a fraction of the thread length (a second knot on the
  // same thread uses another place).
  double jig_x_fraction = 0.3;
  double speed_m_per_s = 0.01;
  double pull_speed_m_per_s = 0.005;
  double pull_tension_N = 0.02;  // the pull stops when both grasps feel this much
  double max_pull_m = 0.02;      // or after moving this far
};

// The thread for the knot tests and benchmarks: stiff nylon 10-0 without gravity (the suture
// floats in fluid), num_nodes nodes at the preset's link length.
ThreadDef KnotTyingDef(int num_nodes);

class KnotTyingScript {
 public:
  // Builds the jig and the waypoint list for `state` (a straight thread along +x, grasped at
  // node 0 by slot b and at node num_nodes - 1 by slot a, which this constructor sets up).
  KnotTyingScript(const ThreadModel& model, ThreadState& state, const KnotTieOptions& options);

  // Advances the script by one step of model.def.time_step_s (moves the grasps, steps the
  // thread). Returns false when the script is over.
  bool Step(const ThreadModel& model, ThreadState& state);
  bool done() const { return done_; }
  const std::vector<Collider>& colliders() const { return colliders_; }
  int slot_a() const { return slot_a_; }
  int slot_b() const { return slot_b_; }

 private:
  struct Waypoint {
    Eigen::Vector3d p_a_W;
    Eigen::Vector3d p_b_W;
    bool pegs_enabled = true;
    bool pull = false;  // move until tension or distance is reached
  };
  KnotTieOptions options_;
  std::vector<Collider> colliders_;
  std::vector<Waypoint> waypoints_;
  int slot_a_ = -1;
  int slot_b_ = -1;
  int segment_ = 0;
  double segment_s_ = 0.0;  // distance travelled along the current segment
  double pulled_m_ = 0.0;
  bool done_ = false;
};

}  // namespace microdex::thread
