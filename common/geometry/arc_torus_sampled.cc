#include "common/geometry/arc_torus_sampled.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/geometry/arc_azimuth_clip.h"
#include "common/geometry/arc_torus_exact.h"

namespace microdex::geometry {

ArcTorusClearance CalcArcTorusClearanceSampled(const ArcDef& arc, const TorusSegmentDef& torus,
                                               int samples) {
  ArcTorusClearance out;
  out.clearance_m = std::numeric_limits<double>::quiet_NaN();
  if (FindArcTorusInputError(arc, torus) != nullptr) {
    out.status = ClearanceStatus::kInvalidInput;
    return out;
  }
  const int n = std::max(2, samples);
  const ArcInTorusFrame f = CalcArcInTorusFrame(arc, torus);
  const bool whole = torus.segment_angle_rad >= 2 * std::numbers::pi;
  // Points by rotation of (cos s, sin s): one sincos for the step, the drift over 10⁴ steps
  // is a few hundred eps, far below the method's own error.
  const double step = f.sweep / (n - 1);
  const double cos_step = std::cos(step), sin_step = std::sin(step);
  double c = 1, s = 0;
  double best_d2 = -1;
  int best_i = -1;
  double best_c = 1, best_s = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = f.center + f.radius * (f.u * c + f.v * s);
    if (whole || IsAzimuthInSegment(p.x(), p.y(), torus.segment_angle_rad)) {
      const double k = std::sqrt(p.x() * p.x() + p.y() * p.y());
      const double d2 = (k - 1) * (k - 1) + p.z() * p.z();
      if (d2 > best_d2) {
        best_d2 = d2;
        best_i = i;
        best_c = c;
        best_s = s;
      }
    }
    const double next_c = c * cos_step - s * sin_step;
    s = s * cos_step + c * sin_step;
    c = next_c;
  }
  if (best_i < 0) {
    out.status = ClearanceStatus::kEmptyRange;
    return out;
  }
  return MakeArcTorusClearance(torus, f, step * best_i, best_c, best_s,
                               std::sqrt(best_d2) * torus.core_radius_m);
}

ArcTorusClearance CalcArcTorusClearanceSampledClipped(const ArcDef& arc,
                                                      const TorusSegmentDef& torus, int samples) {
  ArcTorusClearance out;
  ArcInTorusFrame f;
  AzimuthIntervals iv;
  if (!StartClippedQuery(arc, torus, f, iv, out)) return out;
  double total = 0;
  for (int k = 0; k < iv.count; ++k) total += iv.end[k] - iv.begin[k];
  double best_d2 = -1, best_s = 0, best_c = 1, best_sn = 0;
  for (int k = 0; k < iv.count; ++k) {
    const double width = iv.end[k] - iv.begin[k];
    const int n = std::max(
        2, static_cast<int>(std::lround(samples * (total > 0 ? width / total : 1.0 / iv.count))));
    const double step = width / (n - 1);
    const double cos_step = std::cos(step), sin_step = std::sin(step);
    double c = std::cos(iv.begin[k]), s = std::sin(iv.begin[k]);
    for (int i = 0; i < n; ++i) {
      if (i == n - 1) {  // the piece's end exactly, not by accumulated rotations
        c = std::cos(iv.end[k]);
        s = std::sin(iv.end[k]);
      }
      const Eigen::Vector3d p = f.center + f.radius * (f.u * c + f.v * s);
      const double kk = std::sqrt(p.x() * p.x() + p.y() * p.y());
      const double d2 = (kk - 1) * (kk - 1) + p.z() * p.z();
      if (d2 > best_d2) {
        best_d2 = d2;
        best_s = i == n - 1 ? iv.end[k] : iv.begin[k] + step * i;
        best_c = c;
        best_sn = s;
      }
      const double next_c = c * cos_step - s * sin_step;
      s = s * cos_step + c * sin_step;
      c = next_c;
    }
  }
  return MakeArcTorusClearance(torus, f, best_s, best_c, best_sn,
                               std::sqrt(best_d2) * torus.core_radius_m);
}

}  // namespace microdex::geometry
