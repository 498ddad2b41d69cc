#include "station/loop_module.h"

namespace microdex::station {

LoopModule::LoopModule(const scene::SceneModel& scene)
    : model_(scene.loop->loop, scene.loop->wire),
      wall_stiffness_N_per_m_(scene.loop->wall_stiffness_N_per_m) {}

void LoopModule::InitState(state::StationState& s) const {
  state::LoopModuleState l;
  l.clearance = geometry::CalcLoopWireClearance(model_, Eigen::Isometry3d::Identity());
  l.p_WA_centre = geometry::CalcWireProgress(model_, Eigen::Vector3d::Zero()).p_WA;
  s.loop = l;
}

void LoopModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& f_T_W) {
  state::LoopModuleState& l = *s.loop;
  l.clearance = geometry::CalcLoopWireClearance(model_, in.X_WT);
  const geometry::WireProgress progress = geometry::CalcWireProgress(model_, in.X_WT.translation());
  if (l.clearance.status != geometry::LoopWireStatus::kOk ||
      progress.status != geometry::LoopWireStatus::kOk) {
    ++l.warnings;
    return;  // no force from a failed query
  }
  l.s_m = progress.s_m;
  l.offset_m = progress.distance_m;
  l.p_WA_centre = progress.p_WA;
  if (l.clearance.contact) {
    // Push the loop's nearest circle point C away from the wire's axis point A, in proportion to
    // the depth.
    const Eigen::Vector3d away = l.clearance.p_WC - l.clearance.p_WA;
    const double norm = away.norm();
    if (norm > 0) f_T_W += WallStiffness(s) * (-l.clearance.clearance_m) * (away / norm);
  }
}

ModuleStatus LoopModule::Status(const state::StationState& s) const {
  const state::LoopModuleState& l = *s.loop;
  ModuleStatus st;
  st.fault = l.clearance.status == geometry::LoopWireStatus::kOk && l.clearance.contact;
  st.fault_value = l.clearance.clearance_m;
  st.warnings = l.warnings;
  return st;
}

}  // namespace microdex::station
