#pragma once
// The tissue module (thesis chapter 3, common/fem): the tool tip presses the tissue patch as a
// point (with a contact radius) or as a short bar along the tool's x axis; each tick runs one
// StepTissue on the multi-scale mesh around the tool and renders the reaction force (3.12) to
// the device.
//
// Telemetry: the relative residual ‖b − K u‖ / ‖b‖ of the step's solve is the error estimate
// and failed steps (which keep the last good field and force) are the warnings. A reaction
// above the scene's max_force_N is a fault (pressing too hard). Every mirror period the field
// is sampled on the display grid (uniform, level display_level) into the tissue frame.

#include <vector>

#include "common/fem/tissue_model.h"
#include "common/fem/tissue_step.h"
#include "station/module.h"

namespace microdex::station {

class TissueModule final : public Module {
 public:
  explicit TissueModule(const scene::SceneModel& scene);
  const char* name() const override { return "tissue"; }
  void Step(const ToolInput& in, Eigen::Vector3d& f_T_W) override;
  void WriteSnapshot(TickSnapshot& snapshot) const override;
  void WriteFrame(std::uint64_t step, std::int64_t stamp_ns, LargeFrames& frames) override;
  double error_estimate() const override { return state_.stats.relative_residual; }
  const char* error_kind() const override { return "relative_residual"; }
  std::uint32_t warnings() const override { return state_.num_failed_steps; }
  bool fault() const override { return f_tool_W_.norm() > max_force_N_; }
  double fault_value() const override { return f_tool_W_.norm(); }

  const fem::TissueModel& model() const { return model_; }
  const fem::TissueState& state() const { return state_; }
  const fem::ToolContact& tool() const { return tool_; }
  // The force of the tissue on the tool after the last step, world frame, N (unsaturated).
  const Eigen::Vector3d& f_tool_W() const { return f_tool_W_; }
  // Changes whenever the step's mesh selection changes.
  std::uint32_t mesh_revision() const { return mesh_revision_; }

 private:
  fem::TissueModel model_;
  fem::TissueWorkspace ws_;
  fem::TissueState state_;
  fem::ToolContact tool_;
  Eigen::Isometry3d X_SW_;
  Eigen::Matrix3d R_WS_;
  scene::TissueToolKind tool_kind_;
  double contact_radius_m_;
  double half_bar_m_;
  int display_level_;
  double max_force_N_;
  std::vector<double> grid_m_;  // display grid, sized once
  std::uint32_t mesh_revision_ = 0;
  Eigen::Vector3d f_tool_W_ = Eigen::Vector3d::Zero();
};

}  // namespace microdex::station
