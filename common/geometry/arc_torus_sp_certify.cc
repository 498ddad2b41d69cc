#include "common/geometry/arc_torus_sp_certify.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/geometry/arc_torus_sp_fallback.h"
#include "common/geometry/arc_torus_sp_lift.h"
#include "common/geometry/arc_torus_sp_solve.h"

namespace microdex::geometry {
namespace {

// φ_t below −this·|φ|'s size marks a farther point (the lifted certificate pass).
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

namespace sp {

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

namespace {

// The level t² of a certificate round: the best distance² so far, but not below the thinnest
// level torus the lifted conic resolves.
double CertifyLevelSq(double best_f, double core_r) {
  return std::max(best_f, kMinCertifyRel * kMinCertifyRel * core_r * core_r);
}

}  // namespace

CertifyStep QuickCertify(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                         const SpOptions& opt, Best* best) {
  const double t_sq = CertifyLevelSq(best->f, core_r);
  const double inv_r = 1 / core_r;
  // (ρ/R)² − 1, without cancellation for the needle of the vessel's radius.
  const double rho_sq_minus_one = (nv.rho - core_r) * (nv.rho + core_r) * inv_r * inv_r;
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
  if (tight && ProveNoFartherPoint(level_trig, iv, n_iv, best->s, best->cos_s, best->sin_s, eps,
                                   outer_side)) {
    return CertifyStep::kProved;
  }
  if (tight && IsDeep(best->f, core_r)) {
    // Beyond the horn torus the lifted pass cannot run; the same extrema search runs on
    // G̃_t along the needle instead, with the same error bound.
    Candidate starts[8];
    int n_start = 0;
    if (FindLevelMinimaAlongNeedle(nv, core_r, level_trig, eps, outer_side, iv, n_iv, opt, starts,
                                   &n_start)) {
      const double f_before = best->f;
      for (int j = 0; j < n_start; ++j) TryCandidate(nv, core_r, iv, starts[j], opt, best);
      return best->f > f_before ? CertifyStep::kImproved : CertifyStep::kProvedAlongNeedle;
    }
  }
  return CertifyStep::kNeedsLiftedPass;
}

CertifyStep LiftedCertify(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                          const SpOptions& opt, Best* best, bool* uniform_fallback) {
  const double t_sq = CertifyLevelSq(best->f, core_r);
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
    *uniform_fallback = true;
    AddUniformCandidates(nv, core_r, iv, n_iv, starts, &n_start);
  }
  const double f_before = best->f;
  for (int j = 0; j < n_start; ++j) TryCandidate(nv, core_r, iv, starts[j], opt, best);
  return best->f > f_before ? CertifyStep::kImproved : CertifyStep::kProved;
}

}  // namespace sp
}  // namespace microdex::geometry
