#include "common/geometry/arc_torus_sp_ascent.h"

#include <algorithm>

namespace microdex::geometry::sp {
namespace {

// Budgets of polish_max_iters steps an ascent may use before it stops unconverged.
constexpr int kMaxAscentBudgets = 4;

// A piece end where the distance grows into the piece (the ascent starts there).
bool PointsInward(const Candidate& c) {
  return (c.kind == CandidateKind::kLowEnd && c.df > 0) ||
         (c.kind == CandidateKind::kHighEnd && c.df < 0);
}

}  // namespace

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

bool AddPieceEnds(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv, Candidate* cand,
                  int* n_cand) {
  bool deep = false;
  for (int i = 0; i < n_iv; ++i) {
    for (int end = 0; end < 2; ++end) {
      const Candidate c = end == 0 ? MakeCandidate(nv, core_r, iv[i].lo, iv[i].cos_lo, iv[i].sin_lo,
                                                   i, CandidateKind::kLowEnd)
                                   : MakeCandidate(nv, core_r, iv[i].hi, iv[i].cos_hi, iv[i].sin_hi,
                                                   i, CandidateKind::kHighEnd);
      deep = deep || IsDeep(c.f, core_r);
      cand[(*n_cand)++] = c;
    }
  }
  return deep;
}

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

}  // namespace microdex::geometry::sp
