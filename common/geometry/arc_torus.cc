#include "common/geometry/arc_torus.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace microdex::geometry {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;
// A pose whose linear part is further than this from a rotation is not a rigid placement:
// the needle would not be a circle.
constexpr double kRotationTol = 1e-9;
// Scale ratios beyond this (needle radius or frame distance against R) are rejected: the
// methods work in units of R and powers of these ratios up to the sixth appear.
constexpr double kMaxScaleRatio = 1e9;

bool IsFinitePose(const Eigen::Isometry3d& X) { return X.matrix().allFinite(); }

bool IsRotation(const Eigen::Matrix3d& m) {
  const Eigen::Matrix3d e = m.transpose() * m - Eigen::Matrix3d::Identity();
  return e.cwiseAbs().maxCoeff() <= kRotationTol && m.determinant() > 0;
}

}  // namespace

const char* FindArcTorusInputError(const ArcDef& arc, const TorusSegmentDef& torus) {
  if (!std::isfinite(arc.radius_m) || !(arc.radius_m > 0)) {
    return "ArcDef.radius_m: expected a finite value > 0";
  }
  if (!std::isfinite(arc.sweep_rad) || !(arc.sweep_rad > 0) || arc.sweep_rad > kTwoPi) {
    return "ArcDef.sweep_rad: expected a value in (0, 2π]";
  }
  if (!IsFinitePose(arc.X_WN)) return "ArcDef.X_WN: expected finite entries";
  if (!IsRotation(arc.X_WN.linear())) return "ArcDef.X_WN: linear part is not a rotation";
  if (!std::isfinite(torus.core_radius_m) || !(torus.core_radius_m > 0)) {
    return "TorusSegmentDef.core_radius_m: expected a finite value > 0";
  }
  if (!std::isfinite(torus.tube_radius_m) || !(torus.tube_radius_m > 0)) {
    return "TorusSegmentDef.tube_radius_m: expected a finite value > 0";
  }
  if (!(torus.tube_radius_m < torus.core_radius_m)) {
    return "TorusSegmentDef.tube_radius_m: expected < core_radius_m";
  }
  if (!std::isfinite(torus.segment_angle_rad) || !(torus.segment_angle_rad > 0) ||
      torus.segment_angle_rad > kTwoPi) {
    return "TorusSegmentDef.segment_angle_rad: expected a value in (0, 2π]";
  }
  if (!IsFinitePose(torus.X_WV)) return "TorusSegmentDef.X_WV: expected finite entries";
  if (!IsRotation(torus.X_WV.linear())) {
    return "TorusSegmentDef.X_WV: linear part is not a rotation";
  }
  const double R = torus.core_radius_m;
  if (arc.radius_m > kMaxScaleRatio * R || arc.radius_m < R / kMaxScaleRatio) {
    return "ArcDef.radius_m: expected within 1e9 of core_radius_m either way";
  }
  if ((arc.X_WN.translation() - torus.X_WV.translation()).norm() > kMaxScaleRatio * R) {
    return "ArcDef.X_WN: needle further than 1e9 core radii from the vessel";
  }
  return nullptr;
}

void ValidateArcTorus(const ArcDef& arc, const TorusSegmentDef& torus) {
  if (const char* error = FindArcTorusInputError(arc, torus)) throw std::invalid_argument(error);
}

ArcInTorusFrame CalcArcInTorusFrame(const ArcDef& arc, const TorusSegmentDef& torus) {
  const double R = torus.core_radius_m;
  const Eigen::Matrix3d R_VW = torus.X_WV.linear().transpose();
  const Eigen::Matrix3d R_VN = R_VW * arc.X_WN.linear();
  ArcInTorusFrame f;
  // The difference of the two translations first: both may be far from the origin.
  f.center = R_VW * (arc.X_WN.translation() - torus.X_WV.translation()) / R;
  f.u = R_VN.col(0);
  f.v = R_VN.col(1);
  f.radius = arc.radius_m / R;
  f.radius_minus_one = (arc.radius_m - R) / R;
  f.sweep = arc.sweep_rad;
  return f;
}

bool IsAzimuthInSegment(double x, double y, double segment_angle_rad) {
  if (segment_angle_rad >= kTwoPi) return true;
  double azimuth = std::atan2(y, x);
  if (azimuth < 0) azimuth += kTwoPi;
  return azimuth <= segment_angle_rad;
}

}  // namespace microdex::geometry
