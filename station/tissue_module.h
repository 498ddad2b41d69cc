#pragma once
// The tissue module (thesis chapter 3, common/fem): the tool tip presses the tissue patch as a
// point (with a contact radius) or as a short bar along the tool's x axis; each tick runs one
// StepTissue on the multi-scale mesh around the tool and renders the reaction force (3.12) to
// the device. With tool: needle the tool holds the scene's curved needle at its tail and the
// needle pierces the patch (common/puncture: the tip presses the membrane until it gives way,
// the holes hold the needle with friction and tear when it moves across them).
//
// Telemetry: the relative residual ‖b − K u‖ / ‖b‖ of the step's solve is the error estimate
// and failed steps (which keep the last good field and force) are the warnings. A reaction
// above the scene's max_force_N is a fault (pressing too hard); so is a needle tearing a hole.
// Every mirror period the field is sampled on the display grid (uniform, level display_level) into
// the tissue frame. State: state::TissueModuleState (the displacement field, the last mesh and
// contacts, the force on the tool).
//
// Knot tying on the patch (station/stitch_tissue.h): the suture's loads on the stitch's rods
// (low-passed, in the thread module's section of the state) displace the patch as well; their
// field is added to the one drawn, and the instrument presses a patch displaced by it (the
// superposition of the linear problem: the tool's solve prescribes its depth below the
// displaced surface; the tool's own field does not move the rods).

#include <optional>
#include <vector>

#include "common/fem/tissue_model.h"
#include "common/fem/tissue_step.h"
#include "station/module.h"
#include "station/stitch_tissue.h"

namespace microdex::station {

class TissueModule final : public Module {
 public:
  // stitch: the knot-tying stitch (MakeSharedStitchOnTissue), shared with the thread module;
  // built here when null.
  explicit TissueModule(const scene::SceneModel& scene, SharedStitch stitch = nullptr);
  const char* name() const override { return "tissue"; }
  const char* error_kind() const override { return "relative_residual"; }
  void InitState(state::StationState& state) const override;
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;
  void WriteFrame(const state::StationState& state, std::uint64_t step, std::int64_t stamp_ns,
                  LargeFrames& frames) override;

  const fem::TissueModel& model() const { return model_; }
  // The tool as the last step saw it (derived from the tool pose each step).
  const fem::ToolContact& tool() const { return tool_; }
  // The last step's cost and solver report (telemetry).
  const fem::TissueStepStats& stats() const { return ws_.stats; }
  // Counts the steps whose mesh selection was not in the workspace's cache: a display hint
  // for the view (rebuild the mesh), not simulation state.
  std::uint32_t mesh_revision() const { return mesh_revision_; }

 private:
  fem::TissueModel model_;
  fem::TissueWorkspace ws_;
  fem::ToolContact tool_;
  Eigen::Isometry3d X_SW_;
  Eigen::Matrix3d R_WS_;
  scene::TissueToolKind tool_kind_;
  std::optional<scene::PunctureSceneDef> puncture_;  // tool: needle
  Eigen::Isometry3d X_TN_;                           // the needle's frame on the tool
  double needle_radius_m_, needle_sweep_rad_;
  double contact_radius_m_;
  double half_bar_m_;
  int display_level_;
  double max_force_N_;
  std::vector<double> grid_m_;           // display grid, sized once
  std::vector<double> field_scratch_m_;  // the field on the whole grid (ScatterField), sized once
  std::uint32_t mesh_revision_ = 0;
  SharedStitch stitch_;  // knot tying: the stitch's loads on the patch
};

}  // namespace microdex::station
