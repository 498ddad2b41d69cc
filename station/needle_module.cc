#include "station/needle_module.h"

#include <cmath>
#include <limits>

namespace microdex::station {

NeedleModule::NeedleModule(const scene::SceneModel& scene)
    : X_TN_(scene.X_TN()),
      wall_stiffness_N_per_m_(scene.haptic.wall_stiffness_N_per_m),
      error_estimate_m_(std::numeric_limits<double>::quiet_NaN()) {
  arc_.radius_m = scene.needle.radius_m;
  arc_.sweep_rad = scene.needle.sweep_rad;
  torus_.core_radius_m = scene.vessel.core_radius_m;
  torus_.tube_radius_m = scene.vessel.tube_radius_m;
  torus_.segment_angle_rad = scene.vessel.segment_angle_rad;
  torus_.X_WV = scene.vessel.X_WV;
  arc_.X_WN = scene.CalcIdealX_WT(scene.task.start_azimuth_rad) * X_TN_;
  clearance_ = geometry::CalcArcTorusClearanceSP(arc_, torus_);
}

void NeedleModule::Step(const ToolInput& in, Eigen::Vector3d& f_T_W) {
  arc_.X_WN = in.X_WT * X_TN_;
  clearance_ = geometry::CalcArcTorusClearanceSP(arc_, torus_);
  if (clearance_.status == geometry::ClearanceStatus::kInvalidInput ||
      (clearance_.status == geometry::ClearanceStatus::kOk &&
       !std::isfinite(clearance_.clearance_m))) {
    ++warnings_;
    return;  // no force from a query that failed
  }
  if (clearance_.status == geometry::ClearanceStatus::kOk && clearance_.clearance_m < 0) {
    // Outside the tube by -clearance: push the deepest needle point back towards the wall
    // point nearest to it (inwards), proportionally to the depth.
    const Eigen::Vector3d inward = clearance_.p_WB - clearance_.p_WD;
    const double n = inward.norm();
    if (n > 0) f_T_W += wall_stiffness_N_per_m_ * (-clearance_.clearance_m) * (inward / n);
  }
  if (in.step % kErrorCheckPeriod == 0) {
    const double sampled = CalcSampledClearance(arc_, torus_, kErrorCheckSamples);
    error_estimate_m_ = clearance_.status == geometry::ClearanceStatus::kOk
                            ? std::abs(sampled - clearance_.clearance_m)
                            : std::numeric_limits<double>::quiet_NaN();
  }
}

void NeedleModule::WriteSnapshot(TickSnapshot& s) const {
  s.has_needle = 1;
  const Eigen::Vector3d p = arc_.X_WN.translation();
  const Eigen::Quaterniond q(arc_.X_WN.rotation());
  s.needle.p_WN = {p.x(), p.y(), p.z()};
  s.needle.q_WN = {q.w(), q.x(), q.y(), q.z()};
  s.needle.status = static_cast<std::uint8_t>(clearance_.status);
  const bool ok = clearance_.status == geometry::ClearanceStatus::kOk;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.needle.clearance_m = ok ? clearance_.clearance_m : nan;
  s.needle.contact = ok && clearance_.contact ? 1 : 0;
  s.needle.s_rad = ok ? clearance_.s_rad : nan;
  s.needle.p_WD = {clearance_.p_WD.x(), clearance_.p_WD.y(), clearance_.p_WD.z()};
  s.needle.p_WB = {clearance_.p_WB.x(), clearance_.p_WB.y(), clearance_.p_WB.z()};
}

double CalcSampledClearance(const geometry::ArcDef& arc, const geometry::TorusSegmentDef& torus,
                            int n) {
  const Eigen::Isometry3d X_VN = torus.X_WV.inverse() * arc.X_WN;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const double s = arc.sweep_rad * i / (n - 1);
    const Eigen::Vector3d p_V =
        X_VN * Eigen::Vector3d(arc.radius_m * std::cos(s), arc.radius_m * std::sin(s), 0);
    if (!geometry::IsAzimuthInSegment(p_V.x(), p_V.y(), torus.segment_angle_rad)) continue;
    const double d = std::hypot(std::hypot(p_V.x(), p_V.y()) - torus.core_radius_m, p_V.z());
    best = std::min(best, torus.tube_radius_m - d);
  }
  return std::isfinite(best) ? best : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace microdex::station
