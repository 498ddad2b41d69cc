#include "station/grasp_module.h"

#include "common/grasp/grasp_step.h"

namespace microdex::station {

GraspModule::GraspModule(const scene::SceneModel& scene)
    : model_(grasp::MakeGraspModel(scene.grasp->def)),
      p_W_object_(scene.grasp->p_W_object),
      yaw_rad_(scene.grasp->yaw_rad) {}

void GraspModule::InitState(state::StationState& s) const {
  state::GraspModuleState g;
  g.grasp = grasp::MakeGraspStateOnTable(
      model_, p_W_object_,
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad_, Eigen::Vector3d::UnitZ())));
  s.grasp = g;
}

void GraspModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& f_T_W) {
  grasp::GraspInput gi;
  gi.X_WT = in.X_WT;
  gi.gripper = s.tool.gripper;
  gi.dt_s = in.dt_s;
  grasp::StepGrasp(model_, gi, ws_, s.grasp->grasp);
  f_T_W += s.grasp->grasp.out.f_T_W;
}

Eigen::Vector3d GraspModule::ToolTorque(const state::StationState& s) const {
  return s.grasp->grasp.out.tau_T_W;
}

ModuleStatus GraspModule::Status(const state::StationState& s) const {
  const grasp::GraspState& g = s.grasp->grasp;
  ModuleStatus st;
  // At fault while the object lies dropped: it was lifted and fell out of the jaws.
  st.fault = g.metrics.drops > 0 && !g.metrics.held;
  st.fault_value = g.metrics.drops;
  st.error_estimate = g.out.max_penetration_m;
  st.warnings = static_cast<std::uint32_t>(g.warnings.invalid_inputs + g.warnings.nonfinite_resets +
                                           g.warnings.contact_overflows);
  return st;
}

}  // namespace microdex::station
