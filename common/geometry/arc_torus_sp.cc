#include "common/geometry/arc_torus_sp.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/quartic.h"
#include "common/geometry/stereographic.h"

namespace microdex::geometry {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2 * kPi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The lifted circle's geometry loses about eps/R̂ relative accuracy; below this radius, or
// when its centre and radius are inconsistent with S³, the robust path takes over.
constexpr double kMinLiftedRadius = 1e-9;
constexpr double kLiftedConsistencyTol = 1e-8;
// φ'(θ) below this fraction of |φ|'s size is rounding noise: φ is constant on the circle.
constexpr double kPhiConstantRel = 1e-12;
// When the v of a quartic root cannot be told from −v (βu + δ ≈ 0 or v ≈ 0), keep both.
constexpr double kKeepBothResidual = 1e-6;
// Largest step of the distance ascent [rad of needle parameter].
constexpr double kMaxPolishStep_rad = 0.5;
// Budgets of polish_max_iters steps an ascent may use before it stops unconverged.
constexpr int kMaxAscentBudgets = 4;
// Certificate passes: distances within this fraction of R count as beyond the horn torus;
// below this fraction of R the level torus is too thin for the lifted conic's precision (the
// clearance is then within this of r); φ_t below −this·|φ|'s size marks a farther point.
constexpr double kDeepRel = 1e-6;
constexpr double kMinCertifyRel = 1e-6;
constexpr double kCertifyPhiRel = 1e-12;
// The quick test proves G̃_t ≥ −this·(the size of G̃_t's terms): a fiftieth of the full pass's
// relative threshold, and a few times the rounding of G̃_t's coefficients (below). Smaller is
// better for its error bound, which grows with this (see the tightness test): at 1e-13 it
// could not bound d − t for needles crossing the wall whose terms are ~10³ times t² (ρ and
// |o| of ~2R), which then took the lifted pass.
constexpr double kQuickCertifyRel = 2e-14;
// The rounding of the quick test's polynomial coefficients and of its evaluation, relative to
// the size of G̃_t's terms (~45 ε: products and sums of a few terms, the rotation to s*, the
// τ-polynomial): what the proof's G̃_t ≥ −ε may miss besides ε itself.
constexpr double kLevelTorusRoundingRel = 1e-14;
// What the quick test must prove: no point farther than t + this·max(R, t) (the clearance
// agreement asked of SP is 1e-10 R; the ascent, not this bound, sets the actual error).
constexpr double kQuickCertifyTolRel = 1e-11;
// Beyond the horn torus the quick test skips the needle points with L = |x|² + R² − t² below
// −this·(the size of L's terms): far above L's rounding, so that they are surely nearer than t.
constexpr double kLevelOuterRel = 1e-12;
// Uniform starting points per in-range piece on the robust path.
constexpr int kRobustSamples = 24;

constexpr int kMaxIntervals = 6;
constexpr int kMaxCandidates = 16 + kMaxIntervals * (kRobustSamples + 2);

// A piece [lo, hi] of the needle parameter, with the cosine and sine of its ends.
struct Interval {
  double lo = 0, hi = 0;
  double cos_lo = 1, sin_lo = 0, cos_hi = 1, sin_hi = 0;
};

// The needle circle x(s) = o + ρ(cos s e1 + sin s e2) in the vessel frame V [m].
struct NeedleInV {
  Eigen::Vector3d o, e1, e2, e3;  // e3 = e1 × e2
  double rho = 0, inv_rho = 0;
  Eigen::Vector3d PointAt(double s) const {
    return o + rho * (std::cos(s) * e1 + std::sin(s) * e2);
  }
};

// s ∈ (−4π, 4π) (atan2 and acos sums) to [0, 2π).
double WrapTo2Pi(double s) {
  if (s < 0) s += kTwoPi;
  if (s < 0) s += kTwoPi;
  if (s >= kTwoPi) s -= kTwoPi;
  if (s >= kTwoPi) s -= kTwoPi;
  return s;
}

// cos s and sin s, free at s = 0 (the needle's first point, the usual first piece end).
void CosSin(double s, double* cs, double* sn) {
  if (s == 0) {
    *cs = 1;
    *sn = 0;
    return;
  }
  *cs = std::cos(s);
  *sn = std::sin(s);
}

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

// §4.2.4, last paragraph: the pieces of the arc s ∈ [0, S] whose azimuth lies in [0, Ω]. The
// arc crosses the boundary half-planes (azimuth 0 and Ω) where it crosses their planes through
// the z axis, A cos s + B sin s + C = 0; between consecutive crossings the azimuth test of
// one point decides the whole piece. Every cut carries its (cos s, sin s), from the same
// algebra as s itself, so that neither the test points nor the piece ends need libm.
int ClipArcToSegment(const NeedleInV& nv, double sweep, double cos_sweep, double sin_sweep,
                     double omega, Interval out[]) {
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
    const double a = nv.rho * (nx * nv.e1.x() + ny * nv.e1.y());
    const double b = nv.rho * (nx * nv.e2.x() + ny * nv.e2.y());
    const double c = nx * nv.o.x() + ny * nv.o.y();
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
    if (!InSegment(nv.o + nv.rho * (cm * nv.e1 + sm * nv.e2), omega, cos_omega, sin_omega)) {
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

// f(s) = distance² from x(s) to the core circle, and its first two derivatives in s.
struct CoreDistSq {
  double f = 0, df = 0, d2f = 0;
};

// At the needle point with parameter s, given (cos s, sin s). Scalar code: this is the
// inner loop of the ascent.
inline CoreDistSq EvalCoreDistSq(const NeedleInV& nv, double core_radius, double cs, double sn) {
  const double ax = nv.rho * nv.e1.x(), ay = nv.rho * nv.e1.y(), az = nv.rho * nv.e1.z();
  const double bx = nv.rho * nv.e2.x(), by = nv.rho * nv.e2.y(), bz = nv.rho * nv.e2.z();
  // x(s) = o + cs a + sn b, x' = −sn a + cs b, x'' = o − x.
  const double ux = cs * ax + sn * bx, uy = cs * ay + sn * by, uz = cs * az + sn * bz;
  const double x = nv.o.x() + ux, y = nv.o.y() + uy, z = nv.o.z() + uz;
  const double dx = cs * bx - sn * ax, dy = cs * by - sn * ay, dz = cs * bz - sn * az;
  const double w2 = x * x + y * y;
  const double w = std::sqrt(w2);
  const double e = w - core_radius;
  CoreDistSq r;
  r.f = e * e + z * z;
  if (w <= 1e-12 * core_radius) {
    // On the z axis the distance has a ridge (every core point is equally far): no slope.
    return r;
  }
  const double iw = w * (1 / w2);  // the division runs beside the square root
  const double dw = (x * dx + y * dy) * iw;
  const double d2w = (dx * dx + dy * dy - x * ux - y * uy - dw * dw) * iw;
  r.df = 2 * (e * dw + z * dz);
  r.d2f = 2 * (dw * dw + e * d2w + dz * dz - z * uz);
  return r;
}

// (cos, sin) of s + h from those of s: a rotation by h, with h's cosine and sine from their
// Taylor series (through h¹⁴ and h¹⁵: truncation < 1e-18 for |h| ≤ 0.5, the largest ascent
// step), so that the ascent calls no libm. Both series are polynomials in u = h², evaluated
// by Estrin's scheme (u, u², u⁴ and independent pairs) rather than Horner's: the same terms
// with a third of the dependent multiplications, as this sits on the ascent's critical path.
void AdvanceAngle(double s_new, double h, double* cs, double* sn) {
  if (std::abs(h) <= kMaxPolishStep_rad) {
    // cos h = Σ c_k u^k, sin h / h = Σ d_k u^k, k = 0…7 (c_7 = −1/14!, d_7 = −1/15!).
    constexpr double c0 = 1, c1 = -1.0 / 2, c2 = 1.0 / 24, c3 = -1.0 / 720, c4 = 1.0 / 40320,
                     c5 = -1.0 / 3628800, c6 = 1.0 / 479001600, c7 = -1.0 / 87178291200;
    constexpr double d0 = 1, d1 = -1.0 / 6, d2 = 1.0 / 120, d3 = -1.0 / 5040, d4 = 1.0 / 362880,
                     d5 = -1.0 / 39916800, d6 = 1.0 / 6227020800, d7 = -1.0 / 1307674368000;
    const double u = h * h, u2 = u * u, u4 = u2 * u2;
    const double ch =
        ((c0 + c1 * u) + u2 * (c2 + c3 * u)) + u4 * ((c4 + c5 * u) + u2 * (c6 + c7 * u));
    const double sh =
        h * (((d0 + d1 * u) + u2 * (d2 + d3 * u)) + u4 * ((d4 + d5 * u) + u2 * (d6 + d7 * u)));
    const double c_old = *cs, s_old = *sn;
    *cs = c_old * ch - s_old * sh;
    *sn = s_old * ch + c_old * sh;
  } else {
    *cs = std::cos(s_new);
    *sn = std::sin(s_new);
  }
}

// Safeguarded Newton ascent of the distance² on [iv.lo, iv.hi] from *s (cos = *cs, sin = *sn,
// values *cur there), at most polish_max_iters steps: the Newton step where f is concave, a
// bounded step uphill elsewhere, halved until f does not decrease. Moves (*s, *cs, *sn, *cur)
// to the best point; returns false when the step budget ran out before convergence.
bool AscendCoreDistSq(const NeedleInV& nv, double core_radius, const Interval& iv,
                      const SpOptions& opt, double* s_io, double* cs_io, double* sn_io,
                      CoreDistSq* cur_io) {
  double s = *s_io, cs = *cs_io, sn = *sn_io;
  CoreDistSq cur = *cur_io;
  bool converged = false;
  for (int it = 0; it < opt.polish_max_iters; ++it) {
    const bool newton = cur.d2f < 0;
    double step;
    if (newton) {
      step = -cur.df / cur.d2f;
    } else {
      step = cur.df > 0 ? kMaxPolishStep_rad : (cur.df < 0 ? -kMaxPolishStep_rad : 0.0);
    }
    step = std::clamp(step, -kMaxPolishStep_rad, kMaxPolishStep_rad);
    double s1 = std::clamp(s + step, iv.lo, iv.hi);
    double h = s1 - s;
    // A Newton step this small leaves an error of O(h²) in f: converged.
    if (h == 0 || (newton && std::abs(h) <= opt.polish_tol_rad)) {
      converged = true;
      break;
    }
    double cs1 = cs, sn1 = sn;
    AdvanceAngle(s1, h, &cs1, &sn1);
    CoreDistSq next = EvalCoreDistSq(nv, core_radius, cs1, sn1);
    for (int k = 0; k < 8 && next.f < cur.f; ++k) {
      step *= 0.5;
      s1 = std::clamp(s + step, iv.lo, iv.hi);
      h = s1 - s;
      cs1 = cs;
      sn1 = sn;
      AdvanceAngle(s1, h, &cs1, &sn1);
      next = EvalCoreDistSq(nv, core_radius, cs1, sn1);
    }
    if (next.f < cur.f) {
      converged = true;  // no step uphill left at this resolution
      break;
    }
    s = s1;
    cs = cs1;
    sn = sn1;
    cur = next;
    if (std::abs(h) <= opt.polish_tol_rad) {
      converged = true;
      break;
    }
  }
  *s_io = s;
  *cs_io = cs;
  *sn_io = sn;
  *cur_io = cur;
  return converged;
}

// A starting point of the distance ascent. Piece ends start it only when the distance grows
// into the piece (otherwise the end itself is the local deepest point).
enum class CandidateKind { kLowEnd, kHighEnd, kInterior };
// No member initialisers: the candidate buffer is large and must cost nothing to declare.
struct Candidate {
  double s, cos_s, sin_s;
  int interval;
  CandidateKind kind;
  double f, df, d2f;  // CoreDistSq there, evaluated once (plain: no initialisers)
  CoreDistSq e() const { return {f, df, d2f}; }
};

Candidate MakeCandidate(const NeedleInV& nv, double core_r, double s, double cs, double sn,
                        int interval, CandidateKind kind) {
  const CoreDistSq e = EvalCoreDistSq(nv, core_r, cs, sn);
  return {s, cs, sn, interval, kind, e.f, e.df, e.d2f};
}
// The deep-contact threshold: see kDeepRel.
inline bool IsDeep(double f, double core_r) {
  return f >= (1 - kDeepRel) * (1 - kDeepRel) * core_r * core_r;
}

int FindInterval(const Interval* iv, int n, double s) {
  for (int i = 0; i < n; ++i) {
    if (s >= iv[i].lo && s <= iv[i].hi) return i;
  }
  // Just past an end of a piece by rounding (or s ≈ 2π for a closed needle): snap.
  constexpr double kSnap_rad = 1e-12;
  for (int i = 0; i < n; ++i) {
    if (s >= iv[i].lo - kSnap_rad && s <= iv[i].hi + kSnap_rad) return i;
    if (s - kTwoPi >= iv[i].lo - kSnap_rad && s - kTwoPi <= iv[i].hi + kSnap_rad) return i;
  }
  return -1;
}

}  // namespace

namespace {

// The lifted circle with its axes scaled by its radius, a_x = R̂ b_x and a_y = R̂ b_y: all that
// the conic (4.15) and the map back (4.13) need, formed with three divisions and one square
// root (unit axes cost three more of each, on the critical path of every pass).
struct ScaledLiftedCircle {
  Eigen::Vector4d center, ax, ay;
  double radius_sq = 0;  // R̂²
};

ScaledLiftedCircle LiftCircleScaled(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                    const Eigen::Vector3d& e2, const Eigen::Vector3d& n, double rho,
                                    double inv_rho) {
  // The needle circle is its plane n·x = n·o (n = e1 × e2) cut by its sphere |x − o|² = ρ².
  // Through P (4.2) each becomes a hyperplane of R⁴: n₁·X = h₁ with n₁ = (n, h₁), h₁ = n·o,
  // and n₂·X = h₂ with n₂ = (−2o, 1 − k), h₂ = −(1 + k), k = |o|² − ρ² (substitute
  // x = (l, m, p)/(1 − q), |x|² = (1 + q)/(1 − q)). Their intersection is the plane π of
  // (4.7); its point nearest the origin is the centre c (4.8) = a n₁ + b n₂, from the 2×2
  // Gram system. Here |n₁|² = 1 + h₁², n₁·n₂ = −h₁(1 + k), |n₂|² = 4|o|² + (1 − k)², so its
  // determinant is 4|o|² + (1 − k)² + 4h₁²ρ² (a sum of squares: no cancellation), a = 4h₁ρ²/det
  // and b = −(1 + k)/det. This replaces the triple cross products of (4.7) (no subtraction of
  // nearly equal lifted points) and needs one division (checked against the Gram–Schmidt form
  // and against lifted needle points in arc_torus_sp_test.cc).
  const double h1 = n.dot(o);
  const double o2 = o.squaredNorm(), rho2 = rho * rho;
  const double k = o2 - rho2;
  const double det = 4 * o2 + (1 - k) * (1 - k) + 4 * h1 * h1 * rho2;
  const double a = 4 * h1 * rho2, b = -(1 + k);
  // det · c = a n₁ + b n₂.
  const Eigen::Vector4d c_det(a * n.x() - 2 * b * o.x(), a * n.y() - 2 * b * o.y(),
                              a * n.z() - 2 * b * o.z(), a * h1 + b * (1 - k));
  // (4.9)–(4.10): the first axis through the lift (4.3) of the needle's s = 0 point,
  // X₀ = (2x₀, |x₀|² − 1)/N₀ with N₀ = |x₀|² + 1.
  const Eigen::Vector3d x0 = o + rho * e1;
  const double x0_sq = x0.squaredNorm();
  const double n0 = x0_sq + 1;
  const double inv = 1 / (n0 * det);
  ScaledLiftedCircle lc;
  lc.center = c_det * (n0 * inv);
  const Eigen::Vector4d lifted0(2 * x0.x(), 2 * x0.y(), 2 * x0.z(), x0_sq - 1);
  lc.ax = lifted0 * (det * inv) - lc.center;
  lc.radius_sq = lc.ax.squaredNorm();
  // (4.11)–(4.12): the second axis, the lifted tangent at s = 0, which also orients θ with s.
  // N₀ dP⁻¹(x₀)·ρe₂ = 2(N₀ρe₂ − 2(x₀·ρe₂)x₀, 2x₀·ρe₂)/N₀ has length 2ρ (P⁻¹ is conformal with
  // factor 2/N₀), and it is ⊥ a_x (a tangent of the circle at X₀): scaled to length R̂ it is a_y.
  const Eigen::Vector3d v = rho * e2;
  const double xv = x0.dot(v);
  const Eigen::Vector3d t3 = n0 * v - 2 * xv * x0;  // length N₀ρ together with t's last entry
  const Eigen::Vector4d t(t3.x(), t3.y(), t3.z(), 2 * xv);
  lc.ay = t * (std::sqrt(lc.radius_sq) * det * inv * inv_rho);
  return lc;
}

// (4.15): G = α²(l² + m²) − (p² + q²) at c + cos θ a_x + sin θ a_y.
CircleConic CalcScaledCircleConic(double alpha, const ScaledLiftedCircle& lc) {
  const double a2 = alpha * alpha;
  const auto q = [a2](const Eigen::Vector4d& u, const Eigen::Vector4d& v) {
    return a2 * (u[0] * v[0] + u[1] * v[1]) - u[2] * v[2] - u[3] * v[3];
  };
  CircleConic k;
  k.a = q(lc.ax, lc.ax);
  k.b = 2 * q(lc.ax, lc.ay);
  k.c = q(lc.ay, lc.ay);
  k.d = 2 * q(lc.center, lc.ax);
  k.e = 2 * q(lc.center, lc.ay);
  k.f = q(lc.center, lc.center);
  return k;
}

}  // namespace

LiftedCircle CalcLiftedCircle(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                              const Eigen::Vector3d& e2, double rho) {
  const ScaledLiftedCircle scaled = LiftCircleScaled(o, e1, e2, e1.cross(e2), rho, 1 / rho);
  LiftedCircle lc;
  lc.center = scaled.center;
  lc.radius = std::sqrt(scaled.radius_sq);
  lc.bx = scaled.ax * (1 / lc.radius);
  lc.by = scaled.ay * (1 / lc.radius);
  return lc;
}

namespace {

// x² + y² = w₀c² + w₁cs + w₂s² + w₃c + w₄s + w₅ on the circle x = o + cu + sv,
// (c, s) = (cos s, sin s), as in CalcLevelTorusAlongNeedle.
void AxisDistSqTerms(const Eigen::Vector3d& o, const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                     double w[6]) {
  w[0] = u.x() * u.x() + u.y() * u.y();
  w[1] = 2 * (u.x() * v.x() + u.y() * v.y());
  w[2] = v.x() * v.x() + v.y() * v.y();
  w[3] = 2 * (o.x() * u.x() + o.y() * u.y());
  w[4] = 2 * (o.x() * v.x() + o.y() * v.y());
  w[5] = o.x() * o.x() + o.y() * o.y();
}

// A lower bound of x² + y² on the whole circle: its mean minus the amplitudes of its second
// and first harmonics.
double AxisDistSqLowerBound(const double w[6]) {
  const double h2 = 0.5 * (w[0] - w[2]);
  return w[5] + 0.5 * (w[0] + w[2]) - std::sqrt(h2 * h2 + 0.25 * w[1] * w[1]) -
         std::sqrt(w[3] * w[3] + w[4] * w[4]);
}

// The same for the whole circle's true minimum, less its rounding: the least value at the
// extrema, which (4.17)–(4.26) find for any such polynomial as for φ. Costs a quartic.
double TrigPolyMinimum(const double w[6], const SpOptions& opt) {
  const CircleConic k{w[0], w[1], w[2], w[3], w[4], w[5]};
  double ct[8], st[8];
  bool constant, quartic_fallback;
  const int n = FindConicExtremaOnCircle(k, opt, ct, st, &constant, &quartic_fallback);
  double v = constant ? k.Eval(1, 0) : std::numeric_limits<double>::infinity();
  for (int j = 0; j < n; ++j) v = std::min(v, k.Eval(ct[j], st[j]));
  double size = 0;
  for (int i = 0; i < 6; ++i) size += std::abs(w[i]);
  return v - 1e-15 * size;
}

}  // namespace

CircleConic CalcLevelTorusAlongNeedle(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                      const Eigen::Vector3d& e2, double rho,
                                      double rho_sq_minus_one, double t_sq, double* size,
                                      double* axis_dist_sq_min) {
  // x(s) = o + cos s u + sin s v, u = ρe₁, v = ρe₂, and with L = |x|² − 1 + t² (of degree one
  // in cos s, sin s on a circle: |u|² = |v|² = ρ², u·v = 0),
  // G̃ = 4t²(x² + y²) − 4(1 − t²)z² − L², term by term in cos², cos sin, sin², cos, sin, 1.
  const Eigen::Vector3d u = rho * e1, v = rho * e2;
  double w[6];
  AxisDistSqTerms(o, u, v, w);
  const double z[6] = {u.z() * u.z(),     2 * u.z() * v.z(), v.z() * v.z(),
                       2 * o.z() * u.z(), 2 * o.z() * v.z(), o.z() * o.z()};
  const double kk = o.squaredNorm() + rho_sq_minus_one + t_sq;
  const double p = 2 * o.dot(u), q = 2 * o.dot(v);
  const double l2[6] = {p * p, 2 * p * q, q * q, 2 * kk * p, 2 * kk * q, kk * kk};
  const double a4 = 4 * t_sq, b4 = 4 * (1 - t_sq);
  double c[6];
  double total = 0;
  for (int i = 0; i < 6; ++i) {
    c[i] = a4 * w[i] - b4 * z[i] - l2[i];
    total += std::abs(a4 * w[i]) + std::abs(b4 * z[i]) + std::abs(l2[i]);
  }
  if (size != nullptr) *size = total;
  if (axis_dist_sq_min != nullptr) *axis_dist_sq_min = AxisDistSqLowerBound(w);
  CircleConic k;
  k.a = c[0];
  k.b = c[1];
  k.c = c[2];
  k.d = c[3];
  k.e = c[4];
  k.f = c[5];
  return k;
}

CircleConic CalcCircleConic(double alpha, const LiftedCircle& lc) {
  // (4.15): G = α²(l² + m²) − (p² + q²) at c + x b_x + y b_y, with x = R̂ cos θ, y = R̂ sin θ.
  const double a2 = alpha * alpha;
  const auto q = [a2](const Eigen::Vector4d& u, const Eigen::Vector4d& v) {
    return a2 * (u[0] * v[0] + u[1] * v[1]) - u[2] * v[2] - u[3] * v[3];
  };
  const double rr = lc.radius;
  CircleConic k;
  k.a = q(lc.bx, lc.bx) * rr * rr;
  k.b = 2 * q(lc.bx, lc.by) * rr * rr;
  k.c = q(lc.by, lc.by) * rr * rr;
  k.d = 2 * q(lc.center, lc.bx) * rr;
  k.e = 2 * q(lc.center, lc.by) * rr;
  k.f = q(lc.center, lc.center);
  return k;
}

ExtremaCondition CalcExtremaCondition(const CircleConic& k) {
  // (4.17) on the unit circle: φ'(θ) = B(x² − y²) + 2g xy + E x − D y with g = C − A.
  // (4.19)–(4.20): rotating by ψ turns B(x² − y²) + 2g xy into
  // (u² − v²)(B cos 2ψ + g sin 2ψ) + 2uv(g cos 2ψ − B sin 2ψ). (4.21) as printed sets
  // tan 2ψ = −b/d; the u² − v² term vanishes for tan 2ψ = −B/g, which is used here (checked
  // in arc_torus_sp_test.cc). Then β = 2(g cos 2ψ − B sin 2ψ) = 2√(B² + g²) (4.22), and the
  // linear part E x − D y becomes γ u + δ v with γ = E cos ψ − D sin ψ and
  // δ = −(E sin ψ + D cos ψ) (the printed (4.23) swaps these and drops a sign).
  ExtremaCondition x;
  const double g = k.c - k.a;
  const double n = std::sqrt(k.b * k.b + g * g);
  double c2 = 1, s2 = 0;
  if (n > 0) {
    c2 = g / n;
    s2 = -k.b / n;
  }
  // Half angle of (c2, s2) = (cos 2ψ, sin 2ψ) without trigonometry, stable on both branches.
  if (c2 >= 0) {
    x.cos_psi = std::sqrt(0.5 * (1 + c2));
    x.sin_psi = s2 / (2 * x.cos_psi);
  } else {
    x.sin_psi = std::sqrt(0.5 * (1 - c2));
    if (s2 < 0) x.sin_psi = -x.sin_psi;
    x.cos_psi = s2 / (2 * x.sin_psi);
  }
  x.beta = 2 * n;
  x.gamma = k.e * x.cos_psi - k.d * x.sin_psi;
  x.delta = -(k.e * x.sin_psi + k.d * x.cos_psi);
  return x;
}

int FindConicExtremaOnCircle(const CircleConic& k, const SpOptions& opt, double cos_t[8],
                             double sin_t[8], bool* phi_constant) {
  bool unused;
  return FindConicExtremaOnCircle(k, opt, cos_t, sin_t, phi_constant, &unused);
}

int FindConicExtremaOnCircle(const CircleConic& k, const SpOptions& opt, double cos_t[8],
                             double sin_t[8], bool* phi_constant, bool* quartic_fallback) {
  *quartic_fallback = false;
  const ExtremaCondition x = CalcExtremaCondition(k);
  const double size =
      std::abs(k.a) + std::abs(k.b) + std::abs(k.c) + std::abs(k.d) + std::abs(k.e) + std::abs(k.f);
  const double amp = std::max({x.beta, std::abs(x.gamma), std::abs(x.delta)});
  *phi_constant = !(amp > kPhiConstantRel * size);
  if (*phi_constant) return 0;
  // Normalised so that the quartic's coefficients are O(1).
  const double b = x.beta / amp, g = x.gamma / amp, d = x.delta / amp;
  // (4.24)–(4.26) with R̂ = 1: v = −γu/(βu + δ) on u² + v² = 1 gives
  // β²u⁴ + 2βδu³ + (γ² + δ² − β²)u² − 2βδu − δ² = 0.
  const double quartic[5] = {-d * d, -2 * b * d, g * g + d * d - b * b, 2 * b * d, b * b};
  PolyRootOptions ro;
  ro.tol = opt.quartic_tol;
  ro.max_iters = opt.quartic_max_iters;
  // p(±1) = γ² ≥ 0: extend the interval a little so that roots at u = ±1 show a sign change.
  double roots[4];
  const double lo = -1 - 1e-9, hi = 1 + 1e-9;
  const int nr = opt.quartic_method == SpQuarticMethod::kClosedForm
                     ? SolveQuarticInInterval(quartic, lo, hi, opt.closed_form_polish, ro, roots,
                                              quartic_fallback)
                     : FindPolyRootsInInterval(quartic, lo, hi, ro, roots);
  int n = 0;
  for (int i = 0; i < nr; ++i) {
    const double u = std::clamp(roots[i], -1.0, 1.0);
    const double v0 = std::sqrt(std::max(0.0, 1 - u * u));
    // (4.25) picks the sign of v; evaluate (4.23) for both signs instead of dividing by
    // βu + δ, which vanishes when β = δ = 0 or at the pole of (4.25).
    const double res_pos = std::abs(b * u * v0 + g * u + d * v0);
    const double res_neg = std::abs(-b * u * v0 + g * u - d * v0);
    const bool keep_pos = res_pos <= res_neg || res_pos <= kKeepBothResidual;
    const bool keep_neg = res_neg < res_pos || res_neg <= kKeepBothResidual;
    for (int sgn = 0; sgn < 2; ++sgn) {
      if (!(sgn == 0 ? keep_pos : keep_neg)) continue;
      const double v = sgn == 0 ? v0 : -v0;
      // (4.19): back to the circle's (x, y) = (cos θ, sin θ).
      cos_t[n] = u * x.cos_psi - v * x.sin_psi;
      sin_t[n] = u * x.sin_psi + v * x.cos_psi;
      ++n;
    }
  }
  return n;
}

namespace {

// The lifted needle circle and the conic of the torus of tube radius t on it (appendix B,
// §4.2.3, (4.15)).
struct LiftedConic {
  bool ok = false;  // false: lifted circle too ill-conditioned (README_sp.md, "Fallbacks")
  double lambda = 1, alpha = 0;
  ScaledLiftedCircle lc;
  double radius = 0;  // R̂
  CircleConic conic;
  double phi_size = 0;  // |A| + … + |F|: the scale of φ's values and of their rounding
};

// d2 = R² − t², formed by the caller as accurately as its inputs allow.
void LiftLevelTorus(const NeedleInV& nv, double tube_t, double d2, LiftedConic* out) {
  LiftedConic& k = *out;
  // Appendix B (as CalcTorusLiftScale), then §4.2.3: lift the torus and the needle circle to
  // S³. The square roots of d2 and of t² run side by side.
  const double sd = std::sqrt(d2);  // 1/λ
  k.lambda = 1 / sd;
  k.alpha = tube_t * k.lambda;
  k.lc = LiftCircleScaled(k.lambda * nv.o, nv.e1, nv.e2, nv.e3, k.lambda * nv.rho, sd * nv.inv_rho);
  const ScaledLiftedCircle& lc = k.lc;
  k.radius = std::sqrt(lc.radius_sq);
  k.ok = lc.center.allFinite() && lc.ax.allFinite() && lc.ay.allFinite() &&
         k.radius > kMinLiftedRadius &&
         std::abs(lc.center.squaredNorm() + lc.radius_sq - 1) <= kLiftedConsistencyTol;
  if (!k.ok) return;
  // (4.15), (4.28): the conic on the lifted circle.
  k.conic = CalcScaledCircleConic(k.alpha, lc);
  k.phi_size = std::abs(k.conic.a) + std::abs(k.conic.b) + std::abs(k.conic.c) +
               std::abs(k.conic.d) + std::abs(k.conic.e) + std::abs(k.conic.f);
}

// One SP pass (§4.2.2–§4.2.4) against the torus of core radius R and tube radius t: the
// minima of φ(θ) that lie on the clipped arc, as needle parameters. With `all` set, the
// maxima are kept too (for the sign-change count).
struct SpPass {
  bool ok = false;  // false: lifted circle unusable or φ constant (see diag flags)
  bool lift_ok = false;
  bool phi_constant = false;
  bool quartic_fallback = false;
  double lifted_radius = 0;
  double phi_size = 0;  // |A| + … + |F|: the scale of φ's values and of their rounding
  int n = 0;
  double s[8], cos_s[8], sin_s[8], phi[8];
  bool is_min[8];
  int interval[8];
};

// The extrema part of the pass on an already lifted conic. With phi_below finite, only the
// minima with φ < phi_below·|φ|'s size are kept (and mapped back to the needle), the others
// cost nothing more.
void RunSpPassOnConic(const NeedleInV& nv, const LiftedConic& k, const Interval* iv, int n_iv,
                      const SpOptions& opt, bool all, double phi_below, SpPass* out) {
  SpPass& r = *out;
  r.ok = false;
  r.n = 0;
  r.lifted_radius = k.radius;
  r.lift_ok = k.ok;
  if (!r.lift_ok) return;
  const ScaledLiftedCircle& lc = k.lc;
  const CircleConic& conic = k.conic;
  r.phi_size = k.phi_size;
  // (4.17)–(4.26): the extrema of φ on the lifted circle.
  double ct[8], st[8];
  const int n_ext =
      FindConicExtremaOnCircle(conic, opt, ct, st, &r.phi_constant, &r.quartic_fallback);
  if (r.phi_constant) return;
  r.ok = true;
  const double g = conic.c - conic.a;
  const double d2_scale = std::abs(conic.b) + std::abs(g) + std::abs(conic.d) + std::abs(conic.e);
  for (int j = 0; j < n_ext; ++j) {
    const double c = ct[j], sn = st[j];
    // φ''(θ) = −4B xy + 2g(x² − y²) − D x − E y: minima of φ (and flat points) are the
    // candidates for the deepest point; maxima only matter to the sign-change count.
    const double d2phi =
        -4 * conic.b * c * sn + 2 * g * (c * c - sn * sn) - conic.d * c - conic.e * sn;
    const bool is_min = d2phi >= -1e-9 * d2_scale;
    if (!is_min && !all) continue;
    const double phi = conic.Eval(c, sn);
    if (!(phi < phi_below * r.phi_size)) continue;
    // Back to R³ through (4.13) and P (4.2), then to the needle parameter s.
    const Eigen::Vector4d X = lc.center + (c * lc.ax + sn * lc.ay);
    const Eigen::Vector3d rel = ProjectFromS3(X) / k.lambda - nv.o;
    const double rx = rel.dot(nv.e1), ry = rel.dot(nv.e2);
    const double s = WrapTo2Pi(std::atan2(ry, rx));
    const int i = FindInterval(iv, n_iv, s);
    if (i < 0) continue;
    const double s_in = std::clamp(s, iv[i].lo, iv[i].hi);
    const double inv = 1 / std::sqrt(rx * rx + ry * ry);
    const int m = r.n++;
    r.s[m] = s_in;
    if (s_in == s && std::isfinite(inv)) {
      r.cos_s[m] = rx * inv;
      r.sin_s[m] = ry * inv;
    } else {
      r.cos_s[m] = std::cos(s_in);
      r.sin_s[m] = std::sin(s_in);
    }
    r.phi[m] = phi;
    r.is_min[m] = is_min;
    r.interval[m] = i;
  }
}

void RunSpPass(const NeedleInV& nv, double core_r, double tube_t, const Interval* iv, int n_iv,
               const SpOptions& opt, bool all, double phi_below, SpPass* out) {
  LiftedConic k;
  LiftLevelTorus(nv, tube_t, (core_r - tube_t) * (core_r + tube_t), &k);
  RunSpPassOnConic(nv, k, iv, n_iv, opt, all, phi_below, out);
}

// The minimum of c₁ + c₂τ + c₃τ² + c₄τ³ over [lo, hi] (hi may be +∞): at an end or at a root
// of the derivative c₂ + 2c₃τ + 3c₄τ² inside (stable quadratic formula).
double CubicMinimum(double c1, double c2, double c3, double c4, double lo, double hi) {
  const auto cubic = [&](double tau) { return c1 + tau * (c2 + tau * (c3 + tau * c4)); };
  double v = cubic(lo);
  if (std::isfinite(hi)) {
    v = std::min(v, cubic(hi));
  } else if (!(c4 > 0)) {
    return -std::numeric_limits<double>::infinity();  // unbounded below on [lo, ∞)
  }
  const double qa = 3 * c4, qb = 2 * c3, qc = c2;
  if (qa == 0) {
    if (qb != 0) {
      const double t = -qc / qb;
      if (t > lo && t < hi) v = std::min(v, cubic(t));
    }
    return v;
  }
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return v;
  const double w = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
  for (const double t : {w / qa, w != 0 ? qc / w : 0.0}) {
    if (t > lo && t < hi) v = std::min(v, cubic(t));
  }
  return v;
}

// The certificate's quick test (README_sp.md, "Certificate"). The level torus of tube radius
// t goes through the deepest point found, s*, so G̃_t(s*) ≈ 0 (G̃_t = the lifted torus G_t along
// the needle, CalcLevelTorusAlongNeedle), and G̃_t'(s*) ≈ 0 when the ascent stopped inside a
// piece. With τ = tan((s − s*)/2), q(τ) = (1 + τ²)² G̃_t(s* + Δ) is a quartic
// q₀ + q₁τ + τ² h(τ), h = q₂ + q₃τ + q₄τ². If h ≥ m ≥ 0 on the τ-range of every piece, then
// q ≥ q₀ + q₁τ + mτ² there, and that quadratic's minimum ≥ −ε proves G̃_t ≥ −ε on the clipped
// arc: no point farther than t, without the quartic (4.26). Only sufficient: when it fails,
// the full pass answers.
//
// Beyond the horn torus (t > R) the level set {d = t} is a spindle torus and G̃_t < 0 also in
// its inner lemon, where d < t (README_sp.md, "Deep contacts"): there `outer` gives
// L = |x|² + R² − t² = k + p cos s + q sin s (units of R) and only the parts of the pieces
// where L ≥ −η are tested (d² − t² = L − 2Rw, so L < 0 means d < t whatever G̃_t).
struct LevelOuterSide {
  double k = 0, p = 0, q = 0, eta = 0;
};

bool ProveNoFartherPoint(const CircleConic& q, const Interval* iv, int n_iv, double s_best,
                         double ca, double sa, double eps, const LevelOuterSide* outer) {
  // The trigonometric polynomial rotated to s*: G̃ = A'cos²Δ + B'cosΔ sinΔ + C'sin²Δ + D'cosΔ
  // + E'sinΔ + F.
  const double cc = ca * ca, ss = sa * sa, cs = ca * sa;
  const double a1 = q.a * cc + q.b * cs + q.c * ss;
  const double c1 = q.a * ss - q.b * cs + q.c * cc;
  const double b1 = 2 * (q.c - q.a) * cs + q.b * (cc - ss);
  const double d1 = q.d * ca + q.e * sa;
  const double e1 = q.e * ca - q.d * sa;
  // cos Δ = (1 − τ²)/(1 + τ²), sin Δ = 2τ/(1 + τ²).
  const double k0 = a1 + d1 + q.f;
  const double k1 = 2 * (b1 + e1);
  const double k2 = -2 * a1 + 4 * c1 + 2 * q.f;
  const double k3 = 2 * (e1 - b1);
  const double k4 = a1 - d1 + q.f;
  const auto h = [&](double tau) { return k2 + tau * (k3 + tau * k4); };
  // Minimum of k0 + k1 τ + m τ² over [lo, hi] (infinite ends allowed when m > 0).
  const auto lower_ok = [&](double m, double lo, double hi) {
    double v = std::numeric_limits<double>::infinity();
    if (std::isfinite(lo)) v = std::min(v, k0 + lo * (k1 + lo * m));
    if (std::isfinite(hi)) v = std::min(v, k0 + hi * (k1 + hi * m));
    if (m > 0) {
      const double tv = -k1 / (2 * m);
      if (tv > lo && tv < hi) v = std::min(v, k0 - 0.25 * k1 * k1 / m);
    } else if (!std::isfinite(lo) || !std::isfinite(hi)) {
      return false;
    }
    return v >= -eps;
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // G̃ ≥ −ε for τ ∈ [ta, tb] (either end may be infinite: the range then holds Δ = π, τ = ∞,
  // where G̃ = k₄).
  const auto range_ok = [&](double ta, double tb) {
    if ((!std::isfinite(ta) || !std::isfinite(tb)) && !(k4 > 0)) return false;
    double m = kInf;
    if (std::isfinite(ta)) m = std::min(m, h(ta));
    if (std::isfinite(tb)) m = std::min(m, h(tb));
    if (k4 > 0) {
      const double tv = -k3 / (2 * k4);
      if (tv > ta && tv < tb) m = std::min(m, h(tv));
    }
    if (m >= 0 && lower_ok(m, ta, tb)) return true;
    // A range on one side of s* (s* at its end, or outside it): q = q₀ + τ c(τ) with the
    // cubic c = q₁ + q₂τ + q₃τ² + q₄τ³, so c ≥ 0 on τ ≥ 0 (c ≤ 0 on τ ≤ 0) proves q ≥ q₀.
    // An end that rounding puts just across s* adds a sliver |τ| ≤ 1 where |τ c| ≤ |τ| Σ|qᵢ|:
    // q₀ minus that ≥ −ε/2 there; on the main part c may dip below 0 by rounding as long as
    // τ_max·min c ≥ −(q₀ + ε)/2, which keeps q ≥ (q₀ − ε)/2 ≥ −ε.
    const double sum_k = std::abs(k1) + std::abs(k2) + std::abs(k3) + std::abs(k4);
    if (ta > -1 && tb > 0 && k0 - std::max(0.0, -ta) * sum_k >= -0.5 * eps) {
      const double cm = CubicMinimum(k1, k2, k3, k4, std::max(ta, 0.0), tb);
      if (cm >= 0 || tb * cm >= -0.5 * (k0 + eps)) return true;
    }
    if (tb < 1 && ta < 0 && k0 - std::max(0.0, tb) * sum_k >= -0.5 * eps) {
      const double cm = CubicMinimum(-k1, k2, -k3, k4, std::max(-tb, 0.0), -ta);
      if (cm >= 0 || -ta * cm >= -0.5 * (k0 + eps)) return true;
    }
    return false;
  };
  // τ = tan(Δ/2) = sin Δ / (1 + cos Δ), Δ = s − s* taken in (−π, π).
  const auto tau = [&](double c, double sn) { return (sn * ca - c * sa) / (1 + c * ca + sn * sa); };
  // Ends within this of Δ = ±π are not given a τ (1 + cos Δ → 0): the range is extended past
  // them, to ±∞ or to ±kFarTau (< cot(kNearAntipode_rad/2) ≈ 2000), which is conservative.
  constexpr double kNearAntipode_rad = 1e-3;
  constexpr double kLim = kPi - kNearAntipode_rad;
  constexpr double kFarTau = 1000;
  // Every piece's τ-range by `test` (range_ok, or outer_ok beyond the horn torus; a template
  // so that the common case inlines range_ok).
  const auto all_pieces_ok = [&](const auto& test) {
    for (int i = 0; i < n_iv; ++i) {
      // Δ of the ends, shifted by 2π so that d_lo < π and d_hi > −π (τ is 2π-periodic in Δ).
      double d_lo = iv[i].lo - s_best, d_hi = iv[i].hi - s_best;
      if (d_lo >= kPi) {
        d_lo -= kTwoPi;
        d_hi -= kTwoPi;
      } else if (d_hi <= -kPi) {
        d_lo += kTwoPi;
        d_hi += kTwoPi;
      }
      const double t_lo = tau(iv[i].cos_lo, iv[i].sin_lo), t_hi = tau(iv[i].cos_hi, iv[i].sin_hi);
      bool ok;
      if (d_lo > -kLim && d_hi < kLim) {
        ok = test(t_lo, t_hi);  // Δ ∈ [d_lo, d_hi] ⊂ (−π, π)
      } else if (d_lo > -kLim && d_hi - d_lo < kTwoPi) {
        // Up to and past Δ = π: [τ_lo, ∞), then (past π, Δ − 2π ∈ (−π, d_hi − 2π]) from −∞.
        ok = test(t_lo, kInf) &&
             (d_hi <= kPi || test(-kInf, d_hi - kTwoPi > -kLim ? t_hi : -kFarTau));
      } else if (d_hi < kLim && d_hi - d_lo < kTwoPi) {
        ok = test(-kInf, t_hi) &&
             (d_lo >= -kPi || test(d_lo + kTwoPi < kLim ? t_lo : kFarTau, kInf));
      } else {
        ok = test(-kInf, kInf);  // (nearly) the whole circle
      }
      if (!ok) return false;
    }
    return true;
  };
  if (outer == nullptr) return all_pieces_ok(range_ok);
  // With `outer`: the parts of [ta, tb] where (1 + τ²)(L + η) = aτ² + bτ + c ≥ 0 (L rotated to
  // s* like G̃), each tested by range_ok; the rest has d < t.
  const double lp = outer->p * ca + outer->q * sa, lq = outer->q * ca - outer->p * sa;
  const double la = outer->k + outer->eta - lp, lb = 2 * lq, lc = outer->k + outer->eta + lp;
  const auto outer_ok = [&](double ta, double tb) {
    const auto sub_ok = [&](double lo, double hi) { return !(lo < hi) || range_ok(lo, hi); };
    if (la == 0) {
      if (lb == 0) return !(lc >= 0) || range_ok(ta, tb);
      const double root = -lc / lb;
      return lb > 0 ? sub_ok(std::max(ta, root), tb) : sub_ok(ta, std::min(tb, root));
    }
    const double disc = lb * lb - 4 * la * lc;
    if (!(disc > 0)) return !(la > 0) || range_ok(ta, tb);
    const double w = -0.5 * (lb + std::copysign(std::sqrt(disc), lb));
    const double r1 = std::min(w / la, lc / w), r2 = std::max(w / la, lc / w);
    if (la > 0) return sub_ok(ta, std::min(tb, r1)) && sub_ok(std::max(ta, r2), tb);
    return sub_ok(std::max(ta, r1), std::min(tb, r2));
  };
  return all_pieces_ok(outer_ok);
}

// The certificate's extrema search on G̃_t along the needle (README_sp.md, "Deep contacts"):
// G̃_t is a trigonometric polynomial of degree 2 in the needle parameter s, so (4.17)–(4.26)
// find its extrema on the needle circle as they find φ's on the lifted circle. Where G̃_t ≥ −ε
// at every extremum inside the pieces and outside the spindle's lemon (L ≥ −η, `outer`), it is
// ≥ −ε on the whole clipped arc there: at the piece ends and on the lemon's boundary G̃_t ≥ 0
// up to η² (no end is farther than t). The extrema below −ε are the ascent's next starting
// points (none: no farther point). Returns false when G̃_t is constant along the needle.
bool FindLevelMinimaAlongNeedle(const NeedleInV& nv, double core_r, const CircleConic& g,
                                double eps, const LevelOuterSide* outer, const Interval* iv,
                                int n_iv, const SpOptions& opt, Candidate* starts, int* n_start) {
  double ct[8], st[8];
  bool constant, quartic_fallback;
  const int n_ext = FindConicExtremaOnCircle(g, opt, ct, st, &constant, &quartic_fallback);
  if (constant) return false;
  for (int j = 0; j < n_ext; ++j) {
    const double c = ct[j], sn = st[j];
    if (!(g.Eval(c, sn) < -eps)) continue;
    if (outer != nullptr && outer->k + outer->p * c + outer->q * sn < -outer->eta) continue;
    const double s = WrapTo2Pi(std::atan2(sn, c));
    const int i = FindInterval(iv, n_iv, s);
    if (i < 0) continue;
    const double s_in = std::clamp(s, iv[i].lo, iv[i].hi);
    const double inv = 1 / std::sqrt(c * c + sn * sn);
    double cs = c * inv, ss = sn * inv;
    if (s_in != s) {
      cs = std::cos(s_in);
      ss = std::sin(s_in);
    }
    starts[(*n_start)++] = MakeCandidate(nv, core_r, s_in, cs, ss, i, CandidateKind::kInterior);
  }
  return true;
}

// The deepest point found so far: the needle parameter of the largest distance² to the core.
struct Best {
  double f = -1, s = 0, cos_s = 1, sin_s = 0;
};

// A piece end where the distance grows into the piece (the ascent starts there).
bool PointsInward(const Candidate& c) {
  return (c.kind == CandidateKind::kLowEnd && c.df > 0) ||
         (c.kind == CandidateKind::kHighEnd && c.df < 0);
}

// Distance ascent from one candidate, keeping the best. Returns the f it reached.
double TryCandidate(const NeedleInV& nv, double core_r, const Interval* iv, const Candidate& c,
                    const SpOptions& opt, Best* best) {
  double s = c.s, cs = c.cos_s, sn = c.sin_s;
  double f = c.f;
  const bool ascend =
      opt.polish_max_iters > 0 && (c.kind == CandidateKind::kInterior || PointsInward(c));
  if (ascend) {
    // A long climb (from an arc end, along a needle many times R long, or over the ridge near
    // the axis) may need more than one budget of steps; the certificate bounds the distance
    // only to its tolerance, so the point it certifies must be converged itself.
    CoreDistSq cur = c.e();
    int budgets = 1;
    while (!AscendCoreDistSq(nv, core_r, iv[c.interval], opt, &s, &cs, &sn, &cur) &&
           budgets < kMaxAscentBudgets) {
      // The rotations' rounding drifts (cos, sin) off the unit circle by ~ε per step: back on
      // it after a long climb.
      const double inv = 1 / std::sqrt(cs * cs + sn * sn);
      cs *= inv;
      sn *= inv;
      cur = EvalCoreDistSq(nv, core_r, cs, sn);
      ++budgets;
    }
    f = cur.f;
  }
  if (f > best->f) *best = {f, s, cs, sn};
  return f;
}

void AddUniformCandidates(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                          Candidate* cand, int* n_cand) {
  for (int i = 0; i < n_iv; ++i) {
    for (int j = 1; j <= kRobustSamples; ++j) {
      const double s = iv[i].lo + (iv[i].hi - iv[i].lo) * j / (kRobustSamples + 1);
      cand[(*n_cand)++] =
          MakeCandidate(nv, core_r, s, std::cos(s), std::sin(s), i, CandidateKind::kInterior);
    }
  }
}

// §4.2.4: sign changes of φ along each piece (ends and interior extrema in order of s), and
// the minimum of φ, for the diagnostics.
void CountSignChanges(const NeedleInV& nv, double core_r, double tube_r, const Interval* iv,
                      int n_iv, const SpPass& pass, SpDiagnostics* diag) {
  const TorusLiftScale scale = CalcTorusLiftScale(core_r, tube_r);
  double min_phi = std::numeric_limits<double>::infinity();
  int changes = 0;
  for (int i = 0; i < n_iv; ++i) {
    double s_list[10], phi_list[10];
    int m = 0;
    for (const double s : {iv[i].lo, iv[i].hi}) {
      s_list[m] = s;
      phi_list[m] = EvalLiftedTorus(scale.alpha, LiftToS3(scale.lambda * nv.PointAt(s)));
      ++m;
    }
    for (int j = 0; j < pass.n && m < 10; ++j) {
      if (pass.interval[j] != i) continue;
      s_list[m] = pass.s[j];
      phi_list[m] = pass.phi[j];
      ++m;
    }
    for (int a = 1; a < m; ++a) {  // insertion sort by s
      for (int b = a; b > 0 && s_list[b] < s_list[b - 1]; --b) {
        std::swap(s_list[b], s_list[b - 1]);
        std::swap(phi_list[b], phi_list[b - 1]);
      }
    }
    for (int a = 0; a < m; ++a) {
      min_phi = std::min(min_phi, phi_list[a]);
      if (a > 0 && (phi_list[a] > 0) != (phi_list[a - 1] > 0)) ++changes;
    }
  }
  diag->min_phi = min_phi;
  diag->num_sign_changes = changes;
}

}  // namespace

ArcTorusClearance CalcArcTorusClearanceSP(const ArcDef& arc, const TorusSegmentDef& torus,
                                          const SpOptions& options) {
  return CalcArcTorusClearanceSP(arc, torus, options, nullptr);
}

ArcTorusClearance CalcArcTorusClearanceSP(const ArcDef& arc, const TorusSegmentDef& torus,
                                          const SpOptions& opt, SpDiagnostics* diagnostics) {
  SpDiagnostics local_diag;
  SpDiagnostics& diag = diagnostics != nullptr ? *diagnostics : local_diag;
  diag = SpDiagnostics{};
  ArcTorusClearance out;
  out.clearance_m = kNaN;
  if (FindArcTorusInputError(arc, torus) != nullptr) {
    out.status = ClearanceStatus::kInvalidInput;
    return out;
  }
  const double core_r = torus.core_radius_m;
  const double tube_r = torus.tube_radius_m;

  // The needle circle in the vessel frame V (axes re-orthonormalised).
  const Eigen::Matrix3d R_VW = torus.X_WV.linear().transpose();
  NeedleInV nv;
  nv.o = R_VW * (arc.X_WN.translation() - torus.X_WV.translation());
  // Gram–Schmidt against the unnormalised first axis, so that both normalisations run side by
  // side.
  const Eigen::Vector3d a1 = R_VW * arc.X_WN.linear().col(0);
  const Eigen::Vector3d a2 = R_VW * arc.X_WN.linear().col(1);
  const double a1_sq = a1.squaredNorm();
  nv.e1 = a1 * (1 / std::sqrt(a1_sq));
  nv.e2 = a2 - (a2.dot(a1) / a1_sq) * a1;
  nv.e2 *= 1 / nv.e2.norm();
  nv.e3 = nv.e1.cross(nv.e2);
  nv.rho = arc.radius_m;
  nv.inv_rho = 1 / arc.radius_m;

  // §4.2.4: clip the arc to the segment.
  Interval iv[kMaxIntervals];
  double cos_sweep, sin_sweep;
  CosSin(arc.sweep_rad, &cos_sweep, &sin_sweep);
  const int n_iv =
      ClipArcToSegment(nv, arc.sweep_rad, cos_sweep, sin_sweep, torus.segment_angle_rad, iv);
  diag.num_intervals = n_iv;
  if (n_iv == 0) {
    out.status = ClearanceStatus::kEmptyRange;
    return out;
  }

  Candidate cand[kMaxCandidates];
  int n_cand = 0;
  bool deep = false;
  for (int i = 0; i < n_iv; ++i) {
    for (int end = 0; end < 2; ++end) {
      const Candidate c = end == 0 ? MakeCandidate(nv, core_r, iv[i].lo, iv[i].cos_lo, iv[i].sin_lo,
                                                   i, CandidateKind::kLowEnd)
                                   : MakeCandidate(nv, core_r, iv[i].hi, iv[i].cos_hi, iv[i].sin_hi,
                                                   i, CandidateKind::kHighEnd);
      deep = deep || IsDeep(c.f, core_r);
      cand[n_cand++] = c;
    }
  }

  // The certificate needs the ascent (its starting points are not maxima themselves).
  const int rounds = opt.polish_max_iters > 0 ? opt.max_certify_rounds : 0;
  // The thesis's pass against the vessel wall: its minima of φ with the piece ends decide
  // touch / no-touch, and they start the distance ascent. With the certificate it is the
  // level-set search's first step at t = r; starting that search at the piece ends instead
  // (t = their largest distance) gives the same certified answer with one pass less when an
  // end is the deepest point (README_sp.md).
  const bool wall_pass = rounds == 0 || opt.wall_pass_first || diagnostics != nullptr;
  SpPass pass;
  bool have_pass = false;
  if (wall_pass && (!deep || diagnostics != nullptr)) {
    RunSpPass(nv, core_r, tube_r, iv, n_iv, opt, diagnostics != nullptr,
              std::numeric_limits<double>::infinity(), &pass);
    have_pass = true;
    diag.lifted_radius = pass.lifted_radius;
    diag.phi_constant = pass.phi_constant;
    diag.quartic_fallback = pass.quartic_fallback;
    diag.num_extrema = pass.n;
    if (diagnostics != nullptr && pass.ok) {
      CountSignChanges(nv, core_r, tube_r, iv, n_iv, pass, &diag);
    }
  }
  // Beyond the horn torus (t ≥ R) the level sets are spindle tori, which (4.4) cannot express:
  // there only the quick test can certify (see below), and the exact method answers when it
  // cannot, or when the search starts with the wall pass (wall_pass_first; with diagnostics
  // alone the wall pass only reports, and the search goes on as without them).
  if (deep && (rounds == 0 || !opt.quick_certificate || opt.wall_pass_first)) {
    diag.deep_fallback = true;
    return CalcArcTorusClearanceExact(arc, torus);
  }
  if (have_pass) {
    for (int j = 0; j < pass.n; ++j) {
      if (!pass.is_min[j]) continue;
      cand[n_cand++] = MakeCandidate(nv, core_r, pass.s[j], pass.cos_s[j], pass.sin_s[j],
                                     pass.interval[j], CandidateKind::kInterior);
    }
    if (!pass.ok) {
      // No usable extrema (README_sp.md, "Fallbacks"): start from uniform points instead.
      diag.fallback = true;
      AddUniformCandidates(nv, core_r, iv, n_iv, cand, &n_cand);
    }
  }
  Best best;
  if (rounds > 0 && (!have_pass || pass.ok)) {
    // The certificate below finds any farther point, so only the most promising candidate
    // (largest distance before the ascent) is refined here.
    int j_best = 0;
    double f_best = -1;
    for (int j = 0; j < n_cand; ++j) {
      const double f = cand[j].f;
      if (f > f_best) {
        f_best = f;
        j_best = j;
      }
    }
    TryCandidate(nv, core_r, iv, cand[j_best], opt, &best);
  } else {
    for (int j = 0; j < n_cand; ++j) TryCandidate(nv, core_r, iv, cand[j], opt, &best);
  }

  // Certificate: the extrema of G are not those of the distance, so the ascent may have
  // stopped at a local maximum. The level set {distance = t} with t = the best distance so
  // far is itself a torus (tube radius t); an SP pass against it finds a point farther than
  // t wherever one exists (min φ < 0). Repeat from such a point until none is left.
  if (IsDeep(best.f, core_r) && (rounds == 0 || !opt.quick_certificate)) {
    diag.deep_fallback = true;
    return CalcArcTorusClearanceExact(arc, torus);
  }
  const double inv_r = 1 / core_r;
  // (ρ/R)² − 1, without cancellation for the needle of the vessel's radius.
  const double rho_sq_minus_one = (nv.rho - core_r) * (nv.rho + core_r) * inv_r * inv_r;
  for (int round = 0; round < rounds; ++round) {
    ++diag.certify_passes;
    const double t_sq = std::max(best.f, kMinCertifyRel * kMinCertifyRel * core_r * core_r);
    if (opt.quick_certificate) {
      // G̃_t ≥ −ε on the arc bounds, for any point farther than t, (d² − t²)(d'² − t²) ≤ ε
      // (plus rounding), d' the distance to the opposite core point, with d'² − t² at least
      // R² − t², 4Rw (w the distance to the axis) and √M (below): the quick test is used
      // where that bounds d − t by kQuickCertifyTolRel·max(R, t) (thin level tori near the
      // axis, or needles through the spindle's tips, would not).
      double size;
      const double t_sq_rel = t_sq * inv_r * inv_r;
      const CircleConic level_trig = CalcLevelTorusAlongNeedle(
          inv_r * nv.o, nv.e1, nv.e2, inv_r * nv.rho, rho_sq_minus_one, t_sq_rel, &size);
      const double eps = kQuickCertifyRel * size;
      // ε + rounding ≤ tol · max(1, t) · 2t · (bound of d'² − t²), squared (no square roots).
      const double eps_true = eps + kLevelTorusRoundingRel * size;
      const double lhs = eps_true * eps_true;
      const double rhs =
          4 * kQuickCertifyTolRel * kQuickCertifyTolRel * t_sq_rel * std::max(1.0, t_sq_rel);
      const double near = 1 - t_sq_rel;
      bool tight = near > 0 && lhs <= rhs * near * near;
      LevelOuterSide outer;
      if (!tight) {
        // Deep, or t near R: the bounds through the distance to the axis, d'² − t² ≥ 4Rw, and,
        // beyond the horn torus, through the spindle's tips (below).
        const Eigen::Vector3d o = inv_r * nv.o;
        const Eigen::Vector3d u = inv_r * nv.rho * nv.e1, v = inv_r * nv.rho * nv.e2;
        double w[6];
        AxisDistSqTerms(o, u, v, w);
        double bound = 16 * AxisDistSqLowerBound(w);
        outer.k = o.squaredNorm() + rho_sq_minus_one + 2 - t_sq_rel;
        outer.p = 2 * o.dot(u);
        outer.q = 2 * o.dot(v);
        if (t_sq_rel > 1) {
          // At a point farther than t, L = |x|² + R² − t² = d'² − t² − 2Rw exceeds 2Rw ≥ 0, so
          // (d'² − t²)² ≥ L² + 4R²w² = M, which vanishes only at the spindle's tips (0, 0, ±z_T),
          // z_T² = t² − R², and M ≥ min(1, z_T²)·D², D the distance to the nearer tip (units of
          // R; README_sp.md): D from the distance of the needle circle to each tip.
          const double z_tip_sq = t_sq_rel - 1;
          const double z_tip = std::sqrt(z_tip_sq);
          const double h1 = (o - Eigen::Vector3d(0, 0, z_tip)).dot(nv.e3);
          const double h2 = (o + Eigen::Vector3d(0, 0, z_tip)).dot(nv.e3);
          // In-plane parts: o's in-plane offset from each tip, and ρ.
          const auto in_plane = [&](double zt) {
            const Eigen::Vector3d a = o - Eigen::Vector3d(0, 0, zt);
            const double p1 = a.dot(nv.e1), p2 = a.dot(nv.e2);
            const double gap = std::sqrt(p1 * p1 + p2 * p2) - inv_r * nv.rho;
            return gap * gap;
          };
          const double d_sq = std::min(h1 * h1 + in_plane(z_tip), h2 * h2 + in_plane(-z_tip));
          bound = std::max(bound, std::min(1.0, z_tip_sq) * d_sq);
        }
        tight = bound > 0 && lhs <= rhs * bound;
        if (!tight) {
          // w²'s true minimum on the circle (a quartic: still cheaper than the lifted pass).
          bound = std::max(bound, 16 * TrigPolyMinimum(w, opt));
          tight = bound > 0 && lhs <= rhs * bound;
        }
        // L's rounding is ~ε of this; L < −η is then d < t for sure.
        outer.eta = kLevelOuterRel * (o.squaredNorm() + std::abs(rho_sq_minus_one) + 2 + t_sq_rel +
                                      std::abs(outer.p) + std::abs(outer.q));
      }
      // Only beyond the horn torus can L be negative (|x|² < t² − R²).
      const LevelOuterSide* outer_side = t_sq_rel > 1 ? &outer : nullptr;
      if (tight && ProveNoFartherPoint(level_trig, iv, n_iv, best.s, best.cos_s, best.sin_s, eps,
                                       outer_side)) {
        ++diag.certify_quick;
        break;
      }
      if (tight && IsDeep(best.f, core_r)) {
        // Beyond the horn torus the lifted pass cannot run; the same extrema search runs on
        // G̃_t along the needle instead, with the same error bound.
        Candidate starts[8];
        int n_start = 0;
        if (FindLevelMinimaAlongNeedle(nv, core_r, level_trig, eps, outer_side, iv, n_iv, opt,
                                       starts, &n_start)) {
          const double f_before = best.f;
          for (int j = 0; j < n_start; ++j) TryCandidate(nv, core_r, iv, starts[j], opt, &best);
          if (!(best.f > f_before)) break;
          ++diag.certify_improvements;
          continue;
        }
      }
    }
    if (IsDeep(best.f, core_r)) {
      diag.deep_fallback = true;
      return CalcArcTorusClearanceExact(arc, torus);
    }
    LiftedConic level;
    LiftLevelTorus(nv, std::sqrt(t_sq), core_r * core_r - t_sq, &level);
    SpPass cert;
    RunSpPassOnConic(nv, level, iv, n_iv, opt, false, -kCertifyPhiRel, &cert);
    int n_start = 0;
    Candidate starts[kMaxCandidates];
    if (cert.ok) {
      for (int j = 0; j < cert.n; ++j) {
        if (cert.is_min[j]) {
          starts[n_start++] = MakeCandidate(nv, core_r, cert.s[j], cert.cos_s[j], cert.sin_s[j],
                                            cert.interval[j], CandidateKind::kInterior);
        }
      }
    } else {
      diag.fallback = true;
      AddUniformCandidates(nv, core_r, iv, n_iv, starts, &n_start);
    }
    const double f_before = best.f;
    for (int j = 0; j < n_start; ++j) TryCandidate(nv, core_r, iv, starts[j], opt, &best);
    if (!(best.f > f_before)) break;
    ++diag.certify_improvements;
  }

  const double dist = std::sqrt(best.f);
  const double clearance = tube_r - dist;
  if (!std::isfinite(clearance)) {
    // Finite input whose squares overflow: report it as invalid rather than a NaN.
    out.status = ClearanceStatus::kInvalidInput;
    return out;
  }
  out.status = ClearanceStatus::kOk;
  out.clearance_m = clearance;
  out.contact = clearance <= 0;
  out.s_rad = best.s;
  const Eigen::Vector3d p_VN = nv.o + nv.rho * (best.cos_s * nv.e1 + best.sin_s * nv.e2);
  out.p_WD = torus.X_WV * p_VN;
  // Nearest wall point: along the ray from the nearest core point through the needle point,
  // whose distance from it is dist (f was evaluated at this very point).
  const double w = std::sqrt(p_VN.x() * p_VN.x() + p_VN.y() * p_VN.y());
  const double inv_w = 1 / w, inv_dist = 1 / dist;
  const Eigen::Vector3d radial =
      w > 0 ? Eigen::Vector3d(p_VN.x() * inv_w, p_VN.y() * inv_w, 0) : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d core_pt = core_r * radial;
  const Eigen::Vector3d dir = dist > 0 ? Eigen::Vector3d((p_VN - core_pt) * inv_dist) : radial;
  out.p_WB = torus.X_WV * Eigen::Vector3d(core_pt + tube_r * dir);
  return out;
}

}  // namespace microdex::geometry
