#include "common/geometry/quartic.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace microdex::geometry {
namespace {

// A local extremum of p within this fraction of p's coefficient size from 0 is a double root.
constexpr double kTouchRel = 1e-12;
// Roots closer than this fraction of the interval are reported once.
constexpr double kMergeRel = 1e-7;

// One root of the polynomial k (degree ≤ 4) in [a, b], given p(a)·p(b) < 0: Newton steps
// that stay inside the shrinking bracket, bisection otherwise.
double SolveBracketed(const double k[5], double a, double b, double fa, double fb,
                      const PolyRootOptions& opt) {
  const double d[4] = {k[1], 2 * k[2], 3 * k[3], 4 * k[4]};
  // Regula falsi start: exact for a linear p, good for a well-scaled one.
  double t = a - fa * (b - a) / (fb - fa);
  if (!(t > a && t < b)) t = 0.5 * (a + b);
  for (int it = 0; it < opt.max_iters; ++it) {
    const double f = EvalPoly4(k, t);
    if (f == 0) return t;
    if ((f < 0) == (fa < 0)) {
      a = t;
      fa = f;
    } else {
      b = t;
    }
    const double df = ((d[3] * t + d[2]) * t + d[1]) * t + d[0];
    const double dx = f / df;
    const double next = t - dx;
    if (next > a && next < b) {
      t = next;
      if (std::abs(dx) <= opt.tol) break;
    } else if (std::abs(dx) <= opt.tol) {
      // Converged: the step left the bracket only by rounding.
      break;
    } else {
      t = 0.5 * (a + b);  // also catches df == 0 and NaN
    }
    if (b - a <= opt.tol) break;
  }
  return t;
}

// Real roots in [lo, hi] of the polynomial k, given the sorted critical points crit[0..nc)
// that lie strictly inside (lo, hi): p is monotone between consecutive ones. A critical point
// where |p| ≤ touch_tol is reported as a (double) root: p touches 0 there without a sign
// change that rounding would let the bracketing see.
int RootsOnMonotonePieces(const double k[5], double lo, double hi, const double* crit, int nc,
                          double touch_tol, const PolyRootOptions& opt, double* roots) {
  // Piece ends and the values of p there.
  double x[6], f[6];
  const int m = nc + 2;
  x[0] = lo;
  for (int i = 0; i < nc; ++i) x[i + 1] = crit[i];
  x[m - 1] = hi;
  for (int i = 0; i < m; ++i) f[i] = EvalPoly4(k, x[i]);
  // Roots closer than this are one (a double root splits by ~√eps under rounding).
  const double merge = kMergeRel * (hi - lo);
  int n = 0;
  const auto push = [&](double t) {
    if (n > 0 && t - roots[n - 1] <= merge) return;
    if (n < 4) roots[n++] = t;
  };
  const auto sign_change = [&](int i) {  // across piece i = [x[i], x[i + 1]]
    return f[i] != 0 && f[i + 1] != 0 && (f[i] < 0) != (f[i + 1] < 0);
  };
  for (int i = 0; i < m; ++i) {
    // An exact zero, or p touching 0 at an interior extremum (a double root).
    const bool touches =
        i > 0 && i < m - 1 && std::abs(f[i]) <= touch_tol && !sign_change(i - 1) && !sign_change(i);
    if (f[i] == 0 || touches) push(x[i]);
    if (i + 1 < m && sign_change(i)) push(SolveBracketed(k, x[i], x[i + 1], f[i], f[i + 1], opt));
  }
  return n;
}

// Roots of c0 + c1 t + c2 t² strictly inside (lo, hi), sorted; the stable quadratic formula.
int QuadraticRootsInside(double c0, double c1, double c2, double lo, double hi, double out[2]) {
  double r[2];
  int n = 0;
  if (c2 == 0) {
    if (c1 != 0) r[n++] = -c0 / c1;
  } else {
    const double disc = c1 * c1 - 4 * c2 * c0;
    if (disc >= 0) {
      const double qq = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
      r[n++] = qq / c2;
      if (qq != 0) r[n++] = c0 / qq;
    }
  }
  int m = 0;
  for (int i = 0; i < n; ++i) {
    if (r[i] > lo && r[i] < hi) out[m++] = r[i];
  }
  if (m == 2 && out[0] > out[1]) std::swap(out[0], out[1]);
  return m;
}

}  // namespace

int FindPolyRootsInInterval(const double k[5], double lo, double hi, const PolyRootOptions& opt,
                            double roots[4]) {
  // p ≡ 0 has no isolated roots (and would fill every piece end).
  if (k[0] == 0 && k[1] == 0 && k[2] == 0 && k[3] == 0 && k[4] == 0) return 0;
  // p'' = 2k2 + 6k3 t + 12k4 t²: its roots split (lo, hi) into pieces where p' is monotone.
  double crit2[2];
  const int n2 = QuadraticRootsInside(2 * k[2], 6 * k[3], 12 * k[4], lo, hi, crit2);
  const double dk[5] = {k[1], 2 * k[2], 3 * k[3], 4 * k[4], 0};
  double crit1_all[4];
  const int n1_all = RootsOnMonotonePieces(dk, lo, hi, crit2, n2, 0.0, opt, crit1_all);
  // Keep only the critical points strictly inside, strictly increasing.
  double crit1[4];
  int n1 = 0;
  for (int i = 0; i < n1_all; ++i) {
    const double c = crit1_all[i];
    if (c > lo && c < hi && (n1 == 0 || c > crit1[n1 - 1])) crit1[n1++] = c;
  }
  const double size =
      std::max({std::abs(k[0]), std::abs(k[1]), std::abs(k[2]), std::abs(k[3]), std::abs(k[4])});
  return RootsOnMonotonePieces(k, lo, hi, crit1, n1, kTouchRel * size, opt, roots);
}

namespace {

// Largest real root of m³ + a m² + b m + c (Cardano / Viète).
double LargestCubicRoot(double a, double b, double c) {
  const double a3 = a / 3;
  const double pp = b - a * a3;  // t³ + pp t + qq, m = t − a/3
  const double qq = c - b * a3 + 2 * a3 * a3 * a3;
  const double h = 0.25 * qq * qq + pp * pp * pp / 27;  // discriminant
  double t;
  if (h > 0) {
    const double big = 0.5 * std::abs(qq) + std::sqrt(h);
    const double cb = std::cbrt(big);
    const double u = qq > 0 ? -cb : cb;
    t = u - pp / (3 * u);
  } else {
    const double rr = std::sqrt(std::max(0.0, -pp / 3));
    if (rr == 0) {
      t = 0;
    } else {
      const double cs = std::clamp(-0.5 * qq / (rr * rr * rr), -1.0, 1.0);
      t = 2 * rr * std::cos(std::acos(cs) / 3);
    }
  }
  double m = t - a3;
  // One Newton step against the rounding of the closed form.
  const double f = ((m + a) * m + b) * m + c;
  const double df = (3 * m + 2 * a) * m + b;
  if (df != 0) m -= f / df;
  return m;
}

// Real roots of y² + b y + c, appended to out; a slightly negative discriminant counts as a
// double root so that a tangency is not lost to rounding.
int QuadraticRoots(double b, double c, double tol, double* out) {
  double disc = b * b - 4 * c;
  if (disc < 0) {
    if (disc < -tol) return 0;
    disc = 0;
  }
  const double qq = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  if (qq == 0) {
    out[0] = 0;
    out[1] = 0;
    return 2;
  }
  out[0] = qq;
  out[1] = c / qq;
  return 2;
}

}  // namespace

int SolveQuarticInInterval(const double k[5], double lo, double hi, int newton_polish,
                           const PolyRootOptions& fallback, double roots[4], bool* used_fallback) {
  *used_fallback = false;
  const double scale =
      std::max({std::abs(k[0]), std::abs(k[1]), std::abs(k[2]), std::abs(k[3]), std::abs(k[4])});
  // A leading coefficient this small sends two roots far outside [lo, hi] and makes the monic
  // form ill-conditioned: let the bracketed search (which handles any degree) answer.
  if (!(scale > 0) || std::abs(k[4]) < 1e-6 * scale) {
    *used_fallback = true;
    return FindPolyRootsInInterval(k, lo, hi, fallback, roots);
  }
  const double inv4 = 1 / k[4];
  const double a3 = k[3] * inv4, a2 = k[2] * inv4, a1 = k[1] * inv4, a0 = k[0] * inv4;
  // u = y − a3/4: y⁴ + p y² + q y + r.
  const double sh = 0.25 * a3;
  const double sh2 = sh * sh;
  const double p = a2 - 6 * sh2;
  const double q = a1 - 2 * a2 * sh + 8 * sh2 * sh;
  const double r = a0 - a1 * sh + a2 * sh2 - 3 * sh2 * sh2;
  const double tol = 1e-14 * (1 + std::abs(p) * std::abs(p) + std::abs(r));
  double y[4];
  int ny = 0;
  // Resolvent: (y² + p/2 + m)² = 2m y² − q y + (m² + pm + p²/4 − r) is a square when
  // 8m³ + 8p m² + (2p² − 8r) m − q² = 0.
  const double m = LargestCubicRoot(p, 0.25 * p * p - r, -0.125 * q * q);
  if (m > 1e-12 * (1 + std::abs(p))) {
    const double sq = std::sqrt(2 * m);
    const double off = q / (2 * sq);
    ny += QuadraticRoots(-sq, 0.5 * p + m + off, tol, y + ny);
    ny += QuadraticRoots(sq, 0.5 * p + m - off, tol, y + ny);
  } else {
    // q ≈ 0: biquadratic y⁴ + p y² + r.
    double z[2];
    if (QuadraticRoots(p, r, tol, z) == 2) {
      for (const double zz : z) {
        if (zz >= 0) {
          y[ny++] = std::sqrt(zz);
          y[ny++] = -std::sqrt(zz);
        }
      }
    }
  }
  const double d[4] = {k[1], 2 * k[2], 3 * k[3], 4 * k[4]};
  int n = 0;
  for (int i = 0; i < ny; ++i) {
    double t = y[i] - sh;
    for (int it = 0; it < newton_polish; ++it) {
      const double f = EvalPoly4(k, t);
      const double df = ((d[3] * t + d[2]) * t + d[1]) * t + d[0];
      if (df == 0) break;
      t -= f / df;
    }
    if (!(t >= lo && t <= hi)) continue;
    // Insert sorted, dropping duplicates (swaps: n ≤ 4, cheaper than a block move).
    bool duplicate = n == 4;
    for (int a = 0; a < n && !duplicate; ++a) duplicate = roots[a] == t;
    if (duplicate) continue;
    roots[n] = t;
    for (int a = n; a > 0 && roots[a - 1] > roots[a]; --a) std::swap(roots[a - 1], roots[a]);
    ++n;
  }
  // Check: the sign of p alternates across the roots (simple roots, none missed in between).
  bool ok = true;
  double prev = 0;
  for (int i = 0; i <= n && ok; ++i) {
    const double a = i == 0 ? lo : roots[i - 1];
    const double b = i == n ? hi : roots[i];
    const double mid = EvalPoly4(k, 0.5 * (a + b));
    if (i > 0 && (mid > 0) == (prev > 0)) ok = false;
    prev = mid;
  }
  if (!ok) {
    *used_fallback = true;
    return FindPolyRootsInInterval(k, lo, hi, fallback, roots);
  }
  return n;
}

}  // namespace microdex::geometry
