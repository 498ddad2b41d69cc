#pragma once
// The needle–vessel module: the needle, held at its tail by the tool, against the tube (a
// torus segment). Each step it computes the clearance by the SP method (thesis chapter 4,
// common/geometry/arc_torus_sp.h) and, on contact, a penalty force pushing the tool back
// into the tube (the "impact force when the tool hits a narrow tube" of thesis §2.1).
// Every kErrorCheckPeriod steps it also evaluates the clearance by dense sampling of the arc
// (geometry::CalcArcTorusClearanceSampled) and keeps |SP − sampled| as its error estimate.
// State: state::NeedleState (pose, clearance, error estimate, warnings).

#include "common/geometry/arc_torus.h"
#include "station/module.h"

namespace microdex::station {

class NeedleModule final : public Module {
 public:
  static constexpr int kErrorCheckPeriod = 100;  // steps
  static constexpr int kErrorCheckSamples = 257;

  explicit NeedleModule(const scene::SceneModel& scene);
  const char* name() const override { return "needle"; }
  const char* error_kind() const override { return "sp_vs_sampled_m"; }
  void InitState(state::StationState& state) const override;
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;
  // The wall force acts at the deepest needle point D: (p_WD - p_WT) x f.
  Eigen::Vector3d ToolTorque(const state::StationState& state) const override;

 private:
  // The wall's force on the needle at D for the state's clearance (zero without contact or
  // for a failed query).
  Eigen::Vector3d WallForce(const state::StationState& s) const;
  Eigen::Isometry3d X_TN_;
  // The scene's wall stiffness scaled by the wall cue (0 when it is off).
  double WallStiffness(const state::StationState& s) const {
    return s.cues.on(cues::CueKind::kWall)
               ? wall_stiffness_N_per_m_ * s.cues.p(cues::CueKind::kWall)
               : 0.0;
  }
  double wall_stiffness_N_per_m_;
  geometry::ArcDef arc_;  // the needle's shape, and its pose at the task's start
  geometry::TorusSegmentDef torus_;
};

}  // namespace microdex::station
