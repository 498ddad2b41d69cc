#include "common/cues/path_force_field.h"

#include <algorithm>

namespace microdex::cues {
Eigen::Vector3d CalcPointFieldForce(const Eigen::Vector3d& p_WT, const Eigen::Vector3d& q_W,
                                    double signed_stiffness_N_per_m, double max_force_N) {
  Eigen::Vector3d f = -signed_stiffness_N_per_m * (p_WT - q_W);
  const double n = f.norm();
  if (n > max_force_N) f *= max_force_N / n;
  return f;
}

Eigen::Vector3d CalcNearestOnSegment(const PathSegment& segment, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d d = segment.b_W - segment.a_W;
  const double dd = d.squaredNorm();
  if (!(dd > 0)) return segment.a_W;
  const double u = std::clamp((p_W - segment.a_W).dot(d) / dd, 0.0, 1.0);
  return segment.a_W + u * d;
}

bool CalcNearestOnCircle(const PathCircle& circle, const Eigen::Vector3d& p_W,
                         Eigen::Vector3d* q_W) {
  const Eigen::Vector3d p_C = circle.X_WC.inverse() * p_W;
  const double rho = std::hypot(p_C.x(), p_C.y());
  // Below a nanometre from the axis the direction is rounding noise.
  if (rho < 1e-9) return false;
  const Eigen::Vector3d q_C(circle.radius_m * p_C.x() / rho, circle.radius_m * p_C.y() / rho, 0);
  *q_W = circle.X_WC * q_C;
  return true;
}

Eigen::Vector3d CalcPathFieldForce(const PathCircle& circle, const Eigen::Vector3d& p_WT,
                                   double signed_stiffness_N_per_m, double max_force_N) {
  Eigen::Vector3d q_W;
  if (!CalcNearestOnCircle(circle, p_WT, &q_W)) return Eigen::Vector3d::Zero();
  return CalcPointFieldForce(p_WT, q_W, signed_stiffness_N_per_m, max_force_N);
}

Eigen::Vector3d CalcPathFieldForce(const IdealPath& path, const Eigen::Vector3d& p_WT,
                                   double signed_stiffness_N_per_m, double max_force_N) {
  if (!path.is_segment) {
    return CalcPathFieldForce(path.circle, p_WT, signed_stiffness_N_per_m, max_force_N);
  }
  return CalcPointFieldForce(p_WT, CalcNearestOnSegment(path.segment, p_WT),
                             signed_stiffness_N_per_m, max_force_N);
}

Eigen::Vector3d CalcDivergentFieldForce(const IdealPath& path, const Eigen::Vector3d& p_WT,
                                        double stiffness_N_per_m, double max_force_N) {
  if (!path.is_segment) {
    // p − q is normal to the circle's tangent at its nearest point q already.
    return CalcPathFieldForce(path.circle, p_WT, -stiffness_N_per_m, max_force_N);
  }
  const Eigen::Vector3d q_W = CalcNearestOnSegment(path.segment, p_WT);
  Eigen::Vector3d d = p_WT - q_W;
  const Eigen::Vector3d t = path.segment.b_W - path.segment.a_W;
  const double tt = t.squaredNorm();
  if (tt > 0) d -= (d.dot(t) / tt) * t;  // only the part across the movement
  return CalcPointFieldForce(d, Eigen::Vector3d::Zero(), -stiffness_N_per_m, max_force_N);
}

}  // namespace microdex::cues
