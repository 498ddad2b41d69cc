#pragma once
// The loop-along-a-wire module (thesis §2.2, Fig. 2.2b; common/geometry/loop_wire.h): the tool
// holds a loop (frame L = the tool frame T) and passes it along a wire course. Each tick: the
// loop's clearance to the wire (exact, the needle–tube problem turned round), a penalty force
// pushing the loop off the wire when they touch, and the loop centre's progress along the wire
// and its offset from the wire's axis. Touching is a fault. State: state::LoopModuleState.

#include "common/geometry/loop_wire.h"
#include "station/module.h"

namespace microdex::station {

class LoopModule final : public Module {
 public:
  explicit LoopModule(const scene::SceneModel& scene);
  const char* name() const override { return "loop"; }
  void InitState(state::StationState& state) const override;
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;

  const geometry::LoopWireModel& model() const { return model_; }

 private:
  geometry::LoopWireModel model_;
  // The scene's wall stiffness scaled by the wall cue (0 when it is off).
  double WallStiffness(const state::StationState& s) const {
    return s.cues.on(cues::CueKind::kWall)
               ? wall_stiffness_N_per_m_ * s.cues.p(cues::CueKind::kWall)
               : 0.0;
  }
  double wall_stiffness_N_per_m_;
};

}  // namespace microdex::station
