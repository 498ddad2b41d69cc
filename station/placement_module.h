#pragma once
// The knot-placement module (thesis §2.2: "microsurgeons place knots evenly around the whole
// section, at a constant distance from the end. Misplaced knots risk poor or no blood
// circulation, or blood leak."): a vessel along world z, cut at z = end_height_m; each press of
// a device button (its rising edge) places a stitch where the tool tip is: its azimuth about the
// vessel axis and its distance below the cut edge. Adds no force. State: state::PlacementState.
// CalcPlacementErrors scores them: the angular gaps between neighbouring stitches against
// 2π / n, and the bites against the scene's.

#include "station/module.h"

namespace microdex::station {

struct PlacementErrors {
  double spacing_rms_rad = 0;  // RMS of (gap − 2π / n) over the n gaps, the missing ones 2π / n
  double bite_rms_m = 0;       // RMS of (bite − the scene's bite) over the stitches placed
};
PlacementErrors CalcPlacementErrors(const scene::PlacementSceneDef& def,
                                    const state::PlacementState& placement);

class PlacementModule final : public Module {
 public:
  explicit PlacementModule(const scene::SceneModel& scene);
  const char* name() const override { return "placement"; }
  void InitState(state::StationState& state) const override { state.placement.emplace(); }
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& /*state*/) const override { return {}; }

 private:
  scene::PlacementSceneDef def_;
};

}  // namespace microdex::station
