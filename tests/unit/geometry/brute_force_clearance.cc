#include "tests/unit/geometry/brute_force_clearance.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace microdex::geometry::testing {
namespace {

using Ld = long double;
using Vec3 = Eigen::Matrix<Ld, 3, 1>;
using Mat3 = Eigen::Matrix<Ld, 3, 3>;
constexpr Ld kTwoPiLd = 2 * std::numbers::pi_v<long double>;

class Needle {
 public:
  Needle(const ArcDef& arc, const TorusSegmentDef& torus)
      : rn_(arc.X_WN.linear().cast<Ld>()),
        tn_(arc.X_WN.translation().cast<Ld>()),
        rv_(torus.X_WV.linear().cast<Ld>()),
        tv_(torus.X_WV.translation().cast<Ld>()),
        rho_(arc.radius_m),
        big_r_(torus.core_radius_m),
        omega_(torus.segment_angle_rad),
        whole_(torus.segment_angle_rad >= 2 * std::numbers::pi) {}

  Vec3 PointV(Ld c, Ld s) const {
    const Vec3 p_W = rn_ * Vec3(rho_ * c, rho_ * s, 0) + tn_;
    return rv_.transpose() * (p_W - tv_);
  }
  Vec3 PointV(Ld s) const { return PointV(std::cos(s), std::sin(s)); }

  Ld Distance(const Vec3& p) const {
    const Ld k = std::sqrt(p.x() * p.x() + p.y() * p.y());
    return std::sqrt((k - big_r_) * (k - big_r_) + p.z() * p.z());
  }

  bool Inside(const Vec3& p) const {
    if (whole_) return true;
    Ld azimuth = std::atan2(p.y(), p.x());
    if (azimuth < 0) azimuth += kTwoPiLd;
    return azimuth <= static_cast<Ld>(omega_);
  }

 private:
  Mat3 rn_;
  Vec3 tn_;
  Mat3 rv_;
  Vec3 tv_;
  Ld rho_, big_r_;
  double omega_;
  bool whole_;
};

// The in-range end of the range boundary between a (inside == in_a) and b.
Ld LocateBoundary(const Needle& needle, Ld a, Ld b, bool in_a) {
  for (int it = 0; it < 68; ++it) {
    const Ld mid = 0.5L * (a + b);
    if (mid == a || mid == b) break;
    if (needle.Inside(needle.PointV(mid)) == in_a) {
      a = mid;
    } else {
      b = mid;
    }
  }
  return in_a ? a : b;
}

// Golden-section search for the maximum of the distance on [a, b] (all of it in range).
Ld GoldenMax(const Needle& needle, Ld a, Ld b, Ld* best_s) {
  const Ld g = (std::sqrt(5.0L) - 1) / 2;
  Ld x1 = b - g * (b - a), x2 = a + g * (b - a);
  Ld f1 = needle.Distance(needle.PointV(x1)), f2 = needle.Distance(needle.PointV(x2));
  for (int it = 0; it < 120 && b - a > 1e-19L * std::max<Ld>(1, std::abs(a)); ++it) {
    if (f1 < f2) {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = needle.Distance(needle.PointV(x2));
    } else {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = needle.Distance(needle.PointV(x1));
    }
  }
  Ld best = std::max(f1, f2);
  *best_s = f1 >= f2 ? x1 : x2;
  for (Ld s : {a, b}) {
    const Ld f = needle.Distance(needle.PointV(s));
    if (f > best) {
      best = f;
      *best_s = s;
    }
  }
  return best;
}

}  // namespace

long double BruteForceDistanceToCore(const ArcDef& arc, const TorusSegmentDef& torus,
                                     long double s_rad) {
  const Needle needle(arc, torus);
  return needle.Distance(needle.PointV(s_rad));
}

BruteForceClearance CalcArcTorusClearanceBruteForce(const ArcDef& arc, const TorusSegmentDef& torus,
                                                    int samples) {
  const Needle needle(arc, torus);
  const int n = std::max(samples, 8);
  const Ld sweep = arc.sweep_rad;
  std::vector<Ld> s(n + 1), d(n + 1);
  std::vector<char> in(n + 1);
  // Sample points by exact evaluation every 64 steps and rotation in between.
  const Ld step = sweep / n;
  const Ld cs = std::cos(step), sn = std::sin(step);
  Ld c = 1, si = 0;
  for (int i = 0; i <= n; ++i) {
    if (i % 64 == 0) {
      c = std::cos(step * i);
      si = std::sin(step * i);
    }
    s[i] = i == n ? sweep : step * i;
    const Vec3 p = needle.PointV(c, si);
    in[i] = needle.Inside(p);
    d[i] = needle.Distance(p);
    const Ld next_c = c * cs - si * sn;
    si = si * cs + c * sn;
    c = next_c;
  }
  Ld best = -1, best_s = 0;
  auto consider = [&](Ld sv) {
    const Vec3 p = needle.PointV(sv);
    const Ld dv = needle.Distance(p);
    if (dv > best) {
      best = dv;
      best_s = sv;
    }
  };
  // In-range sub-intervals [lo_i, hi_i] around each in-range sample i.
  std::vector<Ld> lo(n + 1), hi(n + 1);
  for (int i = 0; i <= n; ++i) {
    if (!in[i]) continue;
    lo[i] = i == 0 ? 0 : (in[i - 1] ? s[i - 1] : LocateBoundary(needle, s[i], s[i - 1], true));
    hi[i] = i == n ? sweep : (in[i + 1] ? s[i + 1] : LocateBoundary(needle, s[i], s[i + 1], true));
    if (i == 0 || i == n || !in[i - 1] || !in[i + 1]) {
      consider(s[i]);
      consider(lo[i]);
      consider(hi[i]);
    }
  }
  // In-range pieces between two out-of-range samples.
  for (int i = 0; i + 1 <= n; ++i) {
    if (in[i] || in[i + 1]) continue;
    const Ld mid = 0.5L * (s[i] + s[i + 1]);
    if (needle.Inside(needle.PointV(mid))) {
      consider(LocateBoundary(needle, mid, s[i], true));
      consider(LocateBoundary(needle, mid, s[i + 1], true));
    }
  }
  // Sampled local maxima, refined; the highest few only (a constant distance makes every
  // sample a local maximum).
  std::vector<std::pair<Ld, int>> maxima;
  for (int i = 0; i <= n; ++i) {
    if (!in[i]) continue;
    const bool left_ok = i == 0 || !in[i - 1] || d[i] >= d[i - 1];
    const bool right_ok = i == n || !in[i + 1] || d[i] >= d[i + 1];
    if (left_ok && right_ok) maxima.push_back({d[i], i});
  }
  std::sort(maxima.begin(), maxima.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t j = 0; j < maxima.size() && j < 6; ++j) {
    const int i = maxima[j].second;
    Ld sv;
    const Ld dv = GoldenMax(needle, lo[i], hi[i], &sv);
    if (dv > best) {
      best = dv;
      best_s = sv;
    }
  }
  BruteForceClearance out;
  if (best < 0) return out;
  out.status = ClearanceStatus::kOk;
  out.clearance_m = static_cast<Ld>(torus.tube_radius_m) - best;
  out.s_rad = best_s;
  return out;
}

}  // namespace microdex::geometry::testing
