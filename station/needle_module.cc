#include "station/needle_module.h"

#include <cmath>
#include <limits>

#include "common/geometry/arc_torus_sampled.h"
#include "common/geometry/arc_torus_sp.h"

namespace microdex::station {

NeedleModule::NeedleModule(const scene::SceneModel& scene)
    : X_TN_(scene.X_TN()),
      wall_stiffness_N_per_m_(scene.haptic.wall_stiffness_N_per_m),
      arc_(scene.needle),
      torus_(scene.vessel) {}

void NeedleModule::InitState(state::StationState& s) const {
  state::NeedleState n;
  n.X_WN = arc_.X_WN;
  n.clearance = geometry::CalcArcTorusClearanceSP(arc_, torus_);
  n.error_estimate_m = std::numeric_limits<double>::quiet_NaN();
  s.needle = n;
}

void NeedleModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& f_T_W) {
  state::NeedleState& n = *s.needle;
  geometry::ArcDef arc = arc_;
  arc.X_WN = in.X_WT * X_TN_;
  n.X_WN = arc.X_WN;
  n.clearance = geometry::CalcArcTorusClearanceSP(arc, torus_);
  const geometry::ArcTorusClearance& c = n.clearance;
  if (c.status == geometry::ClearanceStatus::kInvalidInput ||
      (c.status == geometry::ClearanceStatus::kOk && !std::isfinite(c.clearance_m))) {
    ++n.warnings;
    return;  // no force from a query that failed
  }
  f_T_W += WallForce(s);
  if (in.step % kErrorCheckPeriod == 0) {
    const geometry::ArcTorusClearance sampled =
        geometry::CalcArcTorusClearanceSampled(arc, torus_, kErrorCheckSamples);
    n.error_estimate_m = c.status == geometry::ClearanceStatus::kOk &&
                                 sampled.status == geometry::ClearanceStatus::kOk
                             ? std::abs(sampled.clearance_m - c.clearance_m)
                             : std::numeric_limits<double>::quiet_NaN();
  }
}

Eigen::Vector3d NeedleModule::WallForce(const state::StationState& s) const {
  const geometry::ArcTorusClearance& c = s.needle->clearance;
  if (c.status != geometry::ClearanceStatus::kOk || !(c.clearance_m < 0)) {
    return Eigen::Vector3d::Zero();
  }
  // Outside the tube by -clearance: push the deepest needle point D back towards the wall
  // point B nearest to it (inwards), proportionally to the depth.
  const Eigen::Vector3d inward = c.p_WB - c.p_WD;
  const double norm = inward.norm();
  if (!(norm > 0)) return Eigen::Vector3d::Zero();
  return WallStiffness(s) * (-c.clearance_m) * (inward / norm);
}

Eigen::Vector3d NeedleModule::ToolTorque(const state::StationState& s) const {
  const Eigen::Vector3d f = WallForce(s);
  if (f.isZero(0)) return Eigen::Vector3d::Zero();
  return (s.needle->clearance.p_WD - s.tool.X_WT.translation()).cross(f);
}

ModuleStatus NeedleModule::Status(const state::StationState& s) const {
  const state::NeedleState& n = *s.needle;
  ModuleStatus st;
  st.fault = n.clearance.status == geometry::ClearanceStatus::kOk && n.clearance.contact;
  st.fault_value = n.clearance.clearance_m;
  st.error_estimate = n.error_estimate_m;
  st.warnings = n.warnings;
  return st;
}

}  // namespace microdex::station
