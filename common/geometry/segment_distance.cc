#include "common/geometry/segment_distance.h"

#include <algorithm>

namespace microdex::geometry {

SegmentClosest ClosestSegmentSegment(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                     const Eigen::Vector3d& b0, const Eigen::Vector3d& b1) {
  // Squared lengths below this are treated as points; relative to the segments' own scale.
  const Eigen::Vector3d d1 = a1 - a0;
  const Eigen::Vector3d d2 = b1 - b0;
  const Eigen::Vector3d r = a0 - b0;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  const double scale = std::max({a, e, r.squaredNorm(), 1e-300});
  const double eps = 1e-24 * scale;
  double s = 0.0;
  double t = 0.0;
  if (a <= eps && e <= eps) {
    s = t = 0.0;
  } else if (a <= eps) {
    s = 0.0;
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= eps) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentClosest out;
  out.s = s;
  out.t = t;
  out.p = a0 + s * d1;
  out.q = b0 + t * d2;
  out.distance_m = (out.p - out.q).norm();
  return out;
}

double ClosestSegmentPointParam(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = a1 - a0;
  const double len2 = d.squaredNorm();
  if (len2 <= 1e-300) return 0.0;
  return std::clamp((p - a0).dot(d) / len2, 0.0, 1.0);
}

}  // namespace microdex::geometry
