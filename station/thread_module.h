#pragma once
// The suture-thread module (thesis chapter 5, common/thread): node 0 is held at the scene's
// anchor (the stitch) — in a bimanual scene by the second tool, whose tip it follows, with the
// thread's pull on that node rendered to the second device —, the last node is grasped by the
// tool tip and follows it (it starts at
// the tool's ideal start point, the slack bowed as an arc: CalcSlackThreadNodes); each tick
// runs one StepThread (the linearly-implicit integrator of the parameter file at the haptic
// period) and renders the force of the thread on the grasped node (§5.4) to the device.
//
// Telemetry: the largest link strain |l − r| / r after the step is the error estimate (the
// links' inextensibility is the constraint the integrator keeps only approximately), and
// rolled-back steps and contact overflows are the warnings. A strain above the scene's
// max_strain is a fault (an overstretched suture). State: state::ThreadModuleState (the
// thread's nodes, velocities, torsion, grasps, status, and the force on the tool).
//
// Knot tying (task kind knot_tying, scene::KnotTyingSceneDef): the thread is laid through the
// stitch, node 0 in the forceps (second tool) and the last node in the needle holder (first
// tool); the buttons choose the throws, and once all are chosen the module ties them with
// thread::KnotThrowScript (a value in state::KnotTieState), swaps the ends' roles after each
// pull, then holds with thread::KnotHoldScript, the hands' deviations from their rest poses
// then moving the ends. Nothing here allocates: the scripts are fixed-size values.
// With the tissue module the stitch moves with the patch (station/stitch_tissue.h): each step
// the rods sit at their rest plus the patch's displacement under the low-passed loads the
// thread presses on them (state::KnotTieState::stitch_load_N), and after the step those loads
// are updated from the thread's pull where it leaves each rod (thread::CalcColliderLoad).

#include <array>
#include <optional>
#include <vector>

#include "common/thread/colliders.h"
#include "common/thread/knot_tie.h"
#include "common/thread/thread_model.h"
#include "station/module.h"
#include "station/stitch_tissue.h"

namespace microdex::station {

// num_nodes points, equally spaced along a circular arc of length length_m from p_W_a to
// p_W_b (their distance d <= length_m), bowed towards side_W; the straight segment when
// d = length_m. Consecutive points are length_m / (num_nodes − 1) apart along the arc.
Eigen::Matrix3Xd CalcSlackThreadNodes(const Eigen::Vector3d& p_W_a, const Eigen::Vector3d& p_W_b,
                                      const Eigen::Vector3d& side_W, double length_m,
                                      int num_nodes);

// The RMS distance between corresponding columns of x and target after the rigid motion of x
// that best aligns them (Kabsch: centroids, then the rotation from the SVD of the 3 × 3
// covariance, reflections excluded). No allocation.
double CalcAlignedRmsDistance(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& target);

class ThreadModule final : public Module {
 public:
  // Throws std::runtime_error naming the scene field when the thread does not fit the
  // published bound (kMaxFrameThreadNodes nodes).
  // stitch: the knot-tying stitch on the tissue (MakeSharedStitchOnTissue), shared with the
  // tissue module; built here when null.
  explicit ThreadModule(const scene::SceneModel& scene, SharedStitch stitch = nullptr);
  const char* name() const override { return "thread"; }
  const char* error_kind() const override { return "max_link_strain"; }
  void InitState(state::StationState& state) const override;
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;
  Eigen::Vector3d SecondToolForce(const state::StationState& state) const override;
  void WriteFrame(const state::StationState& state, std::uint64_t step, std::int64_t stamp_ns,
                  LargeFrames& frames) override;

  const thread::ThreadModel& model() const { return model_; }
  // Nylon control: the thread's shape at the end of the ideal motion (empty for other tasks).
  const Eigen::Matrix3Xd& target_shape() const { return target_W_; }
  int tool_slot() const { return tool_slot_; }

 private:
  // Knot tying: the throws chosen with the buttons, the guided instrument tie, the pull and
  // the hold (scene::KnotTyingSceneDef).
  void StepKnotTying(const ToolInput& in, state::StationState& state);
  // Knot tying: the options of throw k (0-based) as chosen in the state.
  thread::KnotThrowOptions ThrowOptions(const state::KnotTieState& tie, int k) const;
  // Knot tying on the tissue: the rods where the patch has moved them for the state's loads.
  std::array<thread::Collider, kStitchRods> MovedStitch(const state::KnotTieState& tie) const;
  // ... and the loads updated from the step just taken, whose colliders' last kStitchRods
  // were the rods.
  void UpdateStitchLoads(int num_colliders, const thread::ThreadState& thread,
                         state::KnotTieState& tie) const;

  thread::ThreadModel model_;
  thread::ThreadState initial_;  // at the task's start, both ends grasped
  thread::ThreadWorkspace ws_;
  std::array<thread::Collider, 1> colliders_;
  // Knot tying: the stitch's rods, the options' fixed parts, the hands' rest positions.
  std::optional<scene::KnotTyingSceneDef> tie_;
  std::vector<thread::Collider> stitch_;
  thread::KnotHoldOptions hold_options_;
  SharedStitch stitch_tissue_;  // the stitch moves with the patch
  double stitch_gain_ = 0;      // per step: time step / stitch_relax_s
  // The bite's cut-through (knot_tying.bite_tear_N, 0: none): its threshold, the patch's
  // compliance at the bite, and the cut at which the thread under the bite reaches the surface.
  double bite_tear_N_ = 0;
  double bite_compliance_m_per_N_ = 0;
  double bite_pull_out_m_ = 0;
  Eigen::Vector3d p_W_tool_rest_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_W_second_rest_ = Eigen::Vector3d::Zero();
  int num_colliders_ = 0;
  double floor_z_m_ = 0;  // with a floor (num_colliders_ 1): its height
  int tool_slot_ = -1;
  int tool_node_ = -1;
  int anchor_slot_ = -1;
  bool second_hand_ = false;  // bimanual: the second tool holds node 0 (else it is anchored)
  double max_force_N_;
  double max_strain_;
  // Nylon control: the target, computed at construction by running the task's ideal tool
  // motion (no tremor, no drift) through this thread from the initial state.
  Eigen::Matrix3Xd target_W_;
};

}  // namespace microdex::station
