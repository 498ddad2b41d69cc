#include "common/geometry/arc_azimuth_clip.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace microdex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * kPi;

// IsAzimuthInSegment without atan2 where the point is clearly off both boundary half-planes
// (the sign of y and of the cross product with the direction of azimuth Ω decide); on or
// near a boundary the shared definition answers.
bool InSegment(const Eigen::Vector3d& p, double omega, double cos_omega, double sin_omega) {
  const double cross = cos_omega * p.y() - sin_omega * p.x();  // |p_xy| sin(azimuth − Ω)
  const double tol = 1e-9 * (std::abs(p.x()) + std::abs(p.y()));
  if (std::abs(p.y()) <= tol || std::abs(cross) <= tol) {
    return IsAzimuthInSegment(p.x(), p.y(), omega);
  }
  // Azimuth ∈ (0, π) iff y > 0; azimuth ≤ Ω iff sin(azimuth − Ω) < 0 within the half turn
  // that contains both.
  if (omega <= kPi) return p.y() > 0 && cross < 0;
  return p.y() > 0 || cross < 0;
}

}  // namespace

double WrapTo2Pi(double s) {
  if (s < 0) s += kTwoPi;
  if (s < 0) s += kTwoPi;
  if (s >= kTwoPi) s -= kTwoPi;
  if (s >= kTwoPi) s -= kTwoPi;
  return s;
}

// §4.2.4, last paragraph: the pieces of the arc s ∈ [0, S] whose azimuth lies in [0, Ω]. The
// arc crosses the boundary half-planes (azimuth 0 and Ω) where it crosses their planes through
// the z axis, A cos s + B sin s + C = 0; between consecutive crossings the azimuth test of
// one point decides the whole piece. Every cut carries its (cos s, sin s), from the same
// algebra as s itself, so that neither the test points nor the piece ends need libm.
int ClipArcToAzimuthRange(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                          const Eigen::Vector3d& e2, double rho, double sweep, double cos_sweep,
                          double sin_sweep, double omega, AzimuthPiece out[kMaxAzimuthPieces]) {
  if (omega >= kTwoPi) {
    out[0] = {0, sweep, 1, 0, cos_sweep, sin_sweep};
    return 1;
  }
  struct Cut {
    double s, cs, sn;
  };
  Cut cuts[6];
  int nc = 0;
  cuts[nc++] = {0, 1, 0};
  const auto add_plane = [&](double nx, double ny) {
    const double a = rho * (nx * e1.x() + ny * e1.y());
    const double b = rho * (nx * e2.x() + ny * e2.y());
    const double c = nx * o.x() + ny * o.y();
    const double m = std::sqrt(a * a + b * b);
    if (!(m > 0) || std::abs(c) > m) return;
    // s = β ± η with (cos β, sin β) = (A, B)/m and (cos η, sin η) = (−C, √(m² − C²))/m, by
    // angle addition; s itself (atan2) only for the crossings inside (0, S), which the signs
    // of sin s and of sin(S − s) tell without it.
    const double root = std::sqrt(std::max(0.0, (m - c) * (m + c)));
    const double inv_m2 = 1 / (m * m);
    const double ch = -c, sh = root;  // m (cos η, sin η)
    const double crossings[2][2] = {{(a * ch + b * sh) * inv_m2, (b * ch - a * sh) * inv_m2},
                                    {(a * ch - b * sh) * inv_m2, (b * ch + a * sh) * inv_m2}};
    for (const auto& cs : crossings) {
      const bool inside = sweep <= kPi ? cs[1] > 0 && sin_sweep * cs[0] - cos_sweep * cs[1] > 0
                                       : cs[1] > 0 || sin_sweep * cs[0] - cos_sweep * cs[1] > 0;
      if (!inside) continue;
      const double s = std::clamp(WrapTo2Pi(std::atan2(cs[1], cs[0])), 0.0, sweep);
      cuts[nc++] = {s, cs[0], cs[1]};
    }
  };
  const double cos_omega = std::cos(omega), sin_omega = std::sin(omega);
  add_plane(0, 1);                   // azimuth 0 (and π)
  add_plane(sin_omega, -cos_omega);  // azimuth Ω (and Ω + π)
  cuts[nc++] = {sweep, cos_sweep, sin_sweep};
  for (int a = 1; a < nc; ++a) {  // insertion sort, nc ≤ 6
    for (int b = a; b > 0 && cuts[b].s < cuts[b - 1].s; --b) std::swap(cuts[b], cuts[b - 1]);
  }
  int n = 0;
  for (int i = 0; i + 1 < nc; ++i) {
    const Cut& lo = cuts[i];
    const Cut& hi = cuts[i + 1];
    if (!(hi.s > lo.s)) continue;
    // The midpoint: the bisector of the ends' directions while the piece is shorter than π
    // with a margin (|sum| ≥ 2 cos 1.25 > 0.6), else libm.
    double cm, sm;
    if (hi.s - lo.s <= 2.5) {
      const double x = lo.cs + hi.cs, y = lo.sn + hi.sn;
      const double inv = 1 / std::sqrt(x * x + y * y);
      cm = x * inv;
      sm = y * inv;
    } else {
      cm = std::cos(0.5 * (lo.s + hi.s));
      sm = std::sin(0.5 * (lo.s + hi.s));
    }
    if (!InSegment(o + rho * (cm * e1 + sm * e2), omega, cos_omega, sin_omega)) {
      continue;
    }
    if (n > 0 && out[n - 1].hi == lo.s) {
      out[n - 1].hi = hi.s;
      out[n - 1].cos_hi = hi.cs;
      out[n - 1].sin_hi = hi.sn;
    } else {
      out[n++] = {lo.s, hi.s, lo.cs, lo.sn, hi.cs, hi.sn};
    }
  }
  return n;
}

AzimuthIntervals CalcAzimuthIntervals(const ArcInTorusFrame& arc, double segment_angle_rad) {
  AzimuthIntervals out;
  if (segment_angle_rad >= kTwoPi) {  // the whole torus: no sweep cosine needed
    out.count = 1;
    out.end[0] = arc.sweep;
    return out;
  }
  AzimuthPiece pieces[kMaxAzimuthPieces];
  const int n =
      ClipArcToAzimuthRange(arc.center, arc.u, arc.v, arc.radius, arc.sweep, std::cos(arc.sweep),
                            std::sin(arc.sweep), segment_angle_rad, pieces);
  out.count = n;
  for (int i = 0; i < n; ++i) {
    out.begin[i] = pieces[i].lo;
    out.end[i] = pieces[i].hi;
  }
  return out;
}

bool StartClippedQuery(const ArcDef& arc, const TorusSegmentDef& torus, ArcInTorusFrame& frame,
                       AzimuthIntervals& intervals, ArcTorusClearance& out) {
  out.clearance_m = std::numeric_limits<double>::quiet_NaN();
  if (FindArcTorusInputError(arc, torus) != nullptr) {
    out.status = ClearanceStatus::kInvalidInput;
    return false;
  }
  frame = CalcArcInTorusFrame(arc, torus);
  intervals = CalcAzimuthIntervals(frame, torus.segment_angle_rad);
  if (intervals.count == 0) {
    out.status = ClearanceStatus::kEmptyRange;
    return false;
  }
  return true;
}

}  // namespace microdex::geometry
