#include "common/geometry/arc_azimuth_clip.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace microdex::geometry {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// Parameters s ∈ (0, sweep) where n·p(s) = 0 for the plane through the z axis with normal
// n = (nx, ny, 0): α cos s + β sin s = γ. Appends to s_out, returns the new count.
int AppendPlaneCrossings(const ArcInTorusFrame& arc, double nx, double ny, double* s_out,
                         int count) {
  const double alpha = arc.radius * (nx * arc.u.x() + ny * arc.u.y());
  const double beta = arc.radius * (nx * arc.v.x() + ny * arc.v.y());
  const double gamma = -(nx * arc.center.x() + ny * arc.center.y());
  const double m = std::hypot(alpha, beta);
  if (!(m > 0) || std::abs(gamma) > m) return count;
  const double phi = std::atan2(beta, alpha);
  // acos(γ/m) without the loss of accuracy of acos near ±1.
  const double theta = std::atan2(std::sqrt(std::max(0.0, (m - gamma) * (m + gamma))), gamma);
  for (double s : {phi - theta, phi + theta}) {
    s = std::fmod(s, kTwoPi);
    if (s < 0) s += kTwoPi;
    if (s > 0 && s < arc.sweep) s_out[count++] = s;
  }
  return count;
}

bool IsInside(const ArcInTorusFrame& arc, double s, double segment_angle_rad) {
  const double c = std::cos(s), sn = std::sin(s);
  const double x = arc.center.x() + arc.radius * (arc.u.x() * c + arc.v.x() * sn);
  const double y = arc.center.y() + arc.radius * (arc.u.y() * c + arc.v.y() * sn);
  return IsAzimuthInSegment(x, y, segment_angle_rad);
}

}  // namespace

AzimuthIntervals CalcAzimuthIntervals(const ArcInTorusFrame& arc, double segment_angle_rad) {
  AzimuthIntervals out;
  if (segment_angle_rad >= kTwoPi) {
    out.count = 1;
    out.begin[0] = 0;
    out.end[0] = arc.sweep;
    return out;
  }
  double breaks[6];
  int n = 0;
  breaks[n++] = 0;
  n = AppendPlaneCrossings(arc, 0, 1, breaks, n);  // azimuth 0 (and π): y = 0
  n = AppendPlaneCrossings(arc, std::sin(segment_angle_rad), -std::cos(segment_angle_rad), breaks,
                           n);  // azimuth Ω (and Ω + π)
  // Insertion sort of at most 4 crossings (std::sort trips a false -Warray-bounds here).
  for (int i = 2; i < n; ++i) {
    for (int j = i; j > 1 && breaks[j] < breaks[j - 1]; --j) std::swap(breaks[j], breaks[j - 1]);
  }
  breaks[n++] = arc.sweep;
  bool open = false;
  for (int i = 0; i + 1 < n; ++i) {
    const double a = breaks[i], b = breaks[i + 1];
    if (!(b > a)) continue;
    const bool inside = IsInside(arc, 0.5 * (a + b), segment_angle_rad);
    if (inside && open) {
      out.end[out.count - 1] = b;
    } else if (inside) {
      out.begin[out.count] = a;
      out.end[out.count] = b;
      ++out.count;
    }
    open = inside;
  }
  return out;
}

}  // namespace microdex::geometry
