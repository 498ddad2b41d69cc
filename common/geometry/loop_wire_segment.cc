#include "common/geometry/loop_wire_segment.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/geometry/quartic.h"

namespace microdex::geometry {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr int kMaxRootIters = 200;
// Root brackets are refined to 2ε relative to their ends, and to 2ε R near τ = 0 (the
// distance changes by at most as much: |d'| ≤ 1).
constexpr double kTauFloor = 1;

// The segment's line about its point nearest to the origin (units of R).
struct Line {
  Eigen::Vector3d pc;  // p_c, ⊥ d
  Eigen::Vector3d d;   // unit direction
  double tau_lo = 0;   // τ of the first end (a = p_c + τ_lo d)
  double tau_hi = 0;   // τ of the second end
  double alpha = 0;    // |d_xy|²
  double cross = 0;    // p_xy × d_xy (z component): constant along the line, = ±√α b
};

Line MakeLine(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Line ln;
  const Eigen::Vector3d ab = b - a;
  const double length = ab.norm();
  ln.d = ab / length;
  ln.tau_lo = a.dot(ln.d);
  ln.tau_hi = b.dot(ln.d);
  // p_c from the end nearer to it, so that its rounding is that of the nearer end.
  ln.pc = std::abs(ln.tau_lo) <= std::abs(ln.tau_hi) ? Eigen::Vector3d(a - ln.tau_lo * ln.d)
                                                     : Eigen::Vector3d(b - ln.tau_hi * ln.d);
  ln.alpha = ln.d.x() * ln.d.x() + ln.d.y() * ln.d.y();
  ln.cross = ln.pc.x() * ln.d.y() - ln.pc.y() * ln.d.x();
  return ln;
}

Eigen::Vector3d PointAt(const Line& ln, double tau) { return ln.pc + tau * ln.d; }

// G(τ) = F'(τ)/2 = (k − 1)k' + z z', k' = (p_xy·d_xy)/k, z' = d_z: the same function as
// p·d − k', in the form whose rounding scales with the distance (k − 1, z) rather than with
// |p|: where the nearest point grazes the circle, F' = 2dd' is as small as d, and an error of
// ε in p·d − k' (p_c·d is zero only to rounding) would move the root by ~ε/d. On the z axis
// (k = 0, only where the line crosses it) the one-sided limit of k' is taken: side = +1 from
// above, −1 from below.
double EvalG(const Line& ln, double tau, double side) {
  const double px = ln.pc.x() + tau * ln.d.x(), py = ln.pc.y() + tau * ln.d.y();
  const double pz = ln.pc.z() + tau * ln.d.z();
  const double k = std::sqrt(px * px + py * py);
  const double dk = k > 0 ? (px * ln.d.x() + py * ln.d.y()) / k : side * std::sqrt(ln.alpha);
  return (k - 1) * dk + pz * ln.d.z();
}

// G' = 1 − cross²/k³ (≥ 0 on the pieces searched).
double EvalDG(const Line& ln, double tau) {
  const double px = ln.pc.x() + tau * ln.d.x(), py = ln.pc.y() + tau * ln.d.y();
  const double k2 = px * px + py * py;
  if (!(k2 > 0)) return 1;
  return 1 - ln.cross * ln.cross / (k2 * std::sqrt(k2));
}

// The root of G in [lo, hi] where g_lo = G(lo) < 0 < G(hi) = g_hi, G increasing: Newton
// steps from the secant point, kept inside the bracket, and bisection when a step would leave
// it or would not halve the step before last (Numerical Recipes' rtsafe).
double FindIncreasingRoot(const Line& ln, double lo, double hi, double g_lo, double g_hi,
                          int* iters) {
  double x = lo + (hi - lo) * (g_lo / (g_lo - g_hi));
  if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
  double dx_old = hi - lo, dx = dx_old;
  double g = EvalG(ln, x, 1), dg = EvalDG(ln, x);
  for (int it = 0; it < kMaxRootIters && g != 0; ++it) {
    ++*iters;
    if (g < 0) {
      lo = x;
    } else {
      hi = x;
    }
    const bool newton_leaves = ((x - hi) * dg - g) * ((x - lo) * dg - g) > 0;
    if (newton_leaves || !(dg > 0) || std::abs(2 * g) > std::abs(dx_old * dg)) {
      dx_old = dx;
      dx = 0.5 * (hi - lo);
      x = lo + dx;
    } else {
      dx_old = dx;
      dx = g / dg;
      x -= dx;
    }
    const double tol = 2 * kEps * std::max({std::abs(lo), std::abs(hi), kTauFloor});
    if (std::abs(dx) <= tol || hi - lo <= tol) return x;
    g = EvalG(ln, x, 1);
    dg = EvalDG(ln, x);
  }
  return x;
}

void Consider(const Line& ln, double tau, LoopWirePieceMin* best) {
  const Eigen::Vector3d p = PointAt(ln, tau);
  const double f = CircleDistSq(p);
  if (f < best->dist_sq) {
    best->dist_sq = f;
    best->param = tau - ln.tau_lo;
    best->p = p;
  }
}

}  // namespace

LoopWirePieceMin CalcSegmentCircleMin(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Line ln = MakeLine(a, b);
  LoopWirePieceMin best;
  best.dist_sq = std::numeric_limits<double>::infinity();
  Consider(ln, ln.tau_lo, &best);
  Consider(ln, ln.tau_hi, &best);
  // The increasing pieces of G: all of [τ_lo, τ_hi] when G' ≥ 0 throughout (α ≤ b, i.e.
  // α^{3/2} ≤ |cross|), otherwise the parts outside (τ₀ − σ*, τ₀ + σ*), where
  // k(τ₀ ± σ*)³ = αb² = cross²: σ*² = (|cross|^{4/3} − b²)/α, b² = cross²/α.
  double lo[2] = {ln.tau_lo, 0}, hi[2] = {ln.tau_hi, 0};
  int n = 1;
  const double abs_cross = std::abs(ln.cross);
  if (ln.alpha > 0 && ln.alpha * std::sqrt(ln.alpha) > abs_cross) {
    const double tau0 = -(ln.pc.x() * ln.d.x() + ln.pc.y() * ln.d.y()) / ln.alpha;
    const double b2 = abs_cross * abs_cross / ln.alpha;
    const double k_star = std::cbrt(abs_cross);  // k³ = cross², so k² = |cross|^{4/3}
    const double k_star_sq = k_star * k_star * k_star * k_star;
    const double sigma = std::sqrt(std::max(0.0, k_star_sq - b2) / ln.alpha);
    n = 0;
    if (ln.tau_lo < tau0 - sigma) {
      lo[n] = ln.tau_lo;
      hi[n] = std::min(ln.tau_hi, tau0 - sigma);
      ++n;
    }
    if (ln.tau_hi > tau0 + sigma) {
      lo[n] = std::max(ln.tau_lo, tau0 + sigma);
      hi[n] = ln.tau_hi;
      ++n;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!(hi[i] > lo[i])) continue;
    const double g_lo = EvalG(ln, lo[i], 1), g_hi = EvalG(ln, hi[i], -1);
    if (g_lo >= 0) {
      Consider(ln, lo[i], &best);
    } else if (g_hi <= 0) {
      Consider(ln, hi[i], &best);
    } else {
      Consider(ln, FindIncreasingRoot(ln, lo[i], hi[i], g_lo, g_hi, &best.iterations), &best);
    }
  }
  return best;
}

LoopWirePieceMin CalcSegmentCircleMinQuartic(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Line ln = MakeLine(a, b);
  LoopWirePieceMin best;
  best.dist_sq = std::numeric_limits<double>::infinity();
  Consider(ln, ln.tau_lo, &best);
  Consider(ln, ln.tau_hi, &best);
  // τk = p_xy·d_xy squared: τ²(k_c² + 2c τ + ατ²) − (c + ατ)² = 0, with k_c² = |p_c,xy|²,
  // c = p_c,xy·d_xy.
  const double kc2 = ln.pc.x() * ln.pc.x() + ln.pc.y() * ln.pc.y();
  const double c = ln.pc.x() * ln.d.x() + ln.pc.y() * ln.d.y();
  const double q[5] = {-c * c, -2 * c * ln.alpha, kc2 - ln.alpha * ln.alpha, 2 * c, ln.alpha};
  double roots[4];
  bool used_fallback = false;
  const int nr =
      SolveQuarticInInterval(q, ln.tau_lo, ln.tau_hi, 1, PolyRootOptions{}, roots, &used_fallback);
  for (int i = 0; i < nr; ++i) Consider(ln, roots[i], &best);
  best.iterations = nr;
  best.converged = !used_fallback;
  return best;
}

}  // namespace microdex::geometry
