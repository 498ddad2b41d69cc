#pragma once
// The grasping module (thesis §2.2, Fig. 2.2d; common/grasp): forceps closing on a small object
// on the table. Each tick runs one StepGrasp with the tool pose and the device's gripper value;
// the object's reaction on the jaws is rendered to the device. Dropping a lifted object is a
// fault. State: state::GraspModuleState (the object, the warm-start impulses, the metrics).

#include "common/grasp/grasp_model.h"
#include "station/module.h"

namespace microdex::station {

class GraspModule final : public Module {
 public:
  explicit GraspModule(const scene::SceneModel& scene);
  const char* name() const override { return "grasp"; }
  const char* error_kind() const override { return "max_penetration_m"; }
  void InitState(state::StationState& state) const override;
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;
  // The object's contacts on the jaws about the tool origin (common/grasp, GraspOutput).
  Eigen::Vector3d ToolTorque(const state::StationState& state) const override;

 private:
  grasp::GraspModel model_;
  grasp::GraspWorkspace ws_;
  Eigen::Vector3d p_W_object_;
  double yaw_rad_;
};

}  // namespace microdex::station
