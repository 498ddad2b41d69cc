#include "common/geometry/loop_wire_arc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/quartic.h"

namespace microdex::geometry {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr int kMaxDescentIters = 100;
// Pieces of the local forms: |τ| ≤ tan(π/8) keeps the half-angle quartic well conditioned.
constexpr double kMaxLocalPiece_rad = std::numbers::pi / 2;
// A certificate round counts as progress only when it lowers F by more than this relative
// amount (rounding can make G̃_t slightly positive next to the best point itself).
constexpr double kProgressRel = 64 * kEps;

struct Arc {
  Eigen::Vector3d o, u, v;  // u = ρe₁, v = ρe₂
  double rho = 0, sweep = 0;
  // A step of the descent moves at most this far in s (0.5 R of arc length, at most 0.5 rad).
  double max_step = 0.5;
};

struct Eval {
  double f = 0, df = 0, d2f = 0;
  Eigen::Vector3d p;
};

// F(s) = (k − 1)² + z² and its derivatives (x' = −sin s u + cos s v, x'' = o − x).
Eval EvalF(const Arc& a, double s) {
  const double cs = std::cos(s), sn = std::sin(s);
  const Eigen::Vector3d w = cs * a.u + sn * a.v;
  const Eigen::Vector3d x = a.o + w;
  const Eigen::Vector3d dx = cs * a.v - sn * a.u;
  const double k2 = x.x() * x.x() + x.y() * x.y();
  const double k = std::sqrt(k2);
  Eval e;
  e.p = x;
  e.f = (k - 1) * (k - 1) + x.z() * x.z();
  if (!(k > 0)) {
    // On the z axis: a ridge of F (every core point equally far); no slope across it but z's.
    e.df = 2 * x.z() * dx.z();
    e.d2f = 0;
    return e;
  }
  const double dk = (x.x() * dx.x() + x.y() * dx.y()) / k;
  const double d2k =
      (dx.x() * dx.x() + dx.y() * dx.y() - x.x() * w.x() - x.y() * w.y() - dk * dk) / k;
  e.df = 2 * ((k - 1) * dk + x.z() * dx.z());
  e.d2f = 2 * (dk * dk + (k - 1) * d2k + dx.z() * dx.z() - x.z() * w.z());
  return e;
}

// Safeguarded Newton descent of F on [0, sweep] from s: the Newton step where F is convex, a
// bounded step downhill elsewhere, halved until F does not increase.
void Descend(const Arc& a, double s, LoopWirePieceMin* best) {
  Eval cur = EvalF(a, s);
  for (int it = 0; it < kMaxDescentIters; ++it) {
    ++best->iterations;
    double step = cur.d2f > 0 ? -cur.df / cur.d2f : (cur.df > 0 ? -a.max_step : a.max_step);
    if (cur.df == 0 && !(cur.d2f < 0)) break;
    step = std::clamp(step, -a.max_step, a.max_step);
    double s_new = std::clamp(s + step, 0.0, a.sweep);
    if (s_new == s) break;
    Eval next = EvalF(a, s_new);
    int halvings = 0;
    while (next.f > cur.f && halvings < 60) {
      step *= 0.5;
      s_new = std::clamp(s + step, 0.0, a.sweep);
      next = EvalF(a, s_new);
      ++halvings;
    }
    if (next.f > cur.f) break;
    const double moved = std::abs(s_new - s);
    s = s_new;
    cur = next;
    if (moved <= 4 * kEps * std::max(1.0, std::abs(s))) break;
  }
  if (cur.f < best->dist_sq) {
    best->dist_sq = cur.f;
    best->param = s;
    best->p = cur.p;
  }
}

// s of (cos θ, sin θ) in [0, 2π).
double AngleOf(double c, double s) {
  double t = std::atan2(s, c);
  if (t < 0) t += kTwoPi;
  return t;
}

// One certificate round on the whole circle (the SP query's level torus along the needle,
// and the quartic (4.26) for its extrema): descends from every extremum inside the arc where
// G̃_t > 0.
void CertifyOnWholeCircle(const Arc& a, const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                          const Eigen::Vector3d& e2, double rho, double rho_sq_minus_one,
                          double t_sq, LoopWirePieceMin* best) {
  double size = 0;
  const CircleConic q = CalcLevelTorusAlongNeedle(o, e1, e2, rho, rho_sq_minus_one, t_sq, &size);
  double ct[8], st[8];
  bool constant = false;
  const int n = FindConicExtremaOnCircle(q, SpOptions{}, ct, st, &constant);
  for (int j = 0; j < n; ++j) {
    if (!(q.Eval(ct[j], st[j]) > 0)) continue;
    const double s = AngleOf(ct[j], st[j]);
    if (s > a.sweep) continue;
    Descend(a, s, best);
  }
}

// The same round with the level torus expanded about points of the arc (README.md, "Arcs":
// large or far arcs). Only the part of the arc inside the ball |x| ≤ t + 1 (widened) can be
// closer than t; it is cut into pieces of at most π/2, and on each, about its middle point q,
// x(σ) = q + A(cos σ − 1) + B sin σ (A = ρ × radial, B = ρ × tangent), so that
//   |x|² − 1 + t² = L₀ + 2(o·A)(cos σ − 1) + 2(q·B) sin σ        (|A| = |B| = ρ, A·B = 0),
// and G̃_t = 4t²(x² + y²) − 4(1 − t²)z² − L² is a quadratic form in (cos σ − 1, sin σ) whose
// coefficients are of the size of the quantities near q — no cancellation of terms of size ρ⁴
// or |o|⁴ as in the whole-circle form. With τ = tan(σ/2), (1 + τ²)²G̃_t is a quartic in τ; its
// maxima on the piece are at the ends or at the roots of its derivative (quartic.h).
void CertifyWithLocalForms(const Arc& a, double t_sq, LoopWirePieceMin* best) {
  // |x(s)|² = K + P₁ cos s + P₂ sin s.
  const double K = a.o.squaredNorm() + a.rho * a.rho;
  const double P1 = 2 * a.o.dot(a.u), P2 = 2 * a.o.dot(a.v);
  const double amp = std::hypot(P1, P2);
  const double rb = (std::sqrt(t_sq) + 1) * (1 + 1e-3) + 1e-3;
  double win_lo = 0, win_width = kTwoPi;
  if (amp > 0) {
    const double gamma = (rb * rb - K) / amp;  // inside the ball where cos(s − φ) ≤ γ
    if (gamma <= -1) return;
    if (gamma < 1) {
      const double phi = std::atan2(P2, P1), half = std::acos(gamma);
      win_lo = phi + half;
      win_width = kTwoPi - 2 * half;
    }
  } else if (K > rb * rb) {
    return;
  }
  while (win_lo < 0) win_lo += kTwoPi;
  while (win_lo >= kTwoPi) win_lo -= kTwoPi;
  for (const double shift : {-kTwoPi, 0.0}) {
    const double lo = std::max(0.0, win_lo + shift),
                 hi = std::min(a.sweep, win_lo + win_width + shift);
    if (!(hi > lo)) continue;
    const int pieces = std::max(1, static_cast<int>(std::ceil((hi - lo) / kMaxLocalPiece_rad)));
    for (int i = 0; i < pieces; ++i) {
      const double p0 = lo + (hi - lo) * i / pieces, p1 = lo + (hi - lo) * (i + 1) / pieces;
      const double m = 0.5 * (p0 + p1), half = 0.5 * (p1 - p0);
      const double cm = std::cos(m), sm = std::sin(m);
      const Eigen::Vector3d A = cm * a.u + sm * a.v, B = cm * a.v - sm * a.u;
      const Eigen::Vector3d q = a.o + A;
      const double L0 = q.squaredNorm() - 1 + t_sq, Lc = 2 * a.o.dot(A), Ls = 2 * q.dot(B);
      // Coefficients of 1, c, s, c², cs, s² (c = cos σ − 1, s = sin σ).
      const double kxy[6] = {
          q.x() * q.x() + q.y() * q.y(),       2 * (q.x() * A.x() + q.y() * A.y()),
          2 * (q.x() * B.x() + q.y() * B.y()), A.x() * A.x() + A.y() * A.y(),
          2 * (A.x() * B.x() + A.y() * B.y()), B.x() * B.x() + B.y() * B.y()};
      const double kz[6] = {q.z() * q.z(), 2 * q.z() * A.z(), 2 * q.z() * B.z(),
                            A.z() * A.z(), 2 * A.z() * B.z(), B.z() * B.z()};
      const double kl[6] = {L0 * L0, 2 * L0 * Lc, 2 * L0 * Ls, Lc * Lc, 2 * Lc * Ls, Ls * Ls};
      double g[6];
      for (int j = 0; j < 6; ++j) g[j] = 4 * t_sq * kxy[j] - 4 * (1 - t_sq) * kz[j] - kl[j];
      // (1 + τ²)²·{1, c, s, c², cs, s²} = {(1 + τ²)², −2τ²(1 + τ²), 2τ(1 + τ²), 4τ⁴, −4τ³, 4τ²}.
      const double poly[5] = {g[0], 2 * g[2], 2 * g[0] - 2 * g[1] + 4 * g[5], 2 * g[2] - 4 * g[4],
                              g[0] - 2 * g[1] + 4 * g[3]};
      const double dpoly[5] = {poly[1], 2 * poly[2], 3 * poly[3], 4 * poly[4], 0};
      const double tau_hi = std::tan(0.5 * half);
      double roots[4];
      const int nr = FindPolyRootsInInterval(dpoly, -tau_hi, tau_hi, PolyRootOptions{}, roots);
      double cand[6];
      int nc = 0;
      cand[nc++] = -tau_hi;
      cand[nc++] = tau_hi;
      for (int j = 0; j < nr; ++j) cand[nc++] = roots[j];
      for (int j = 0; j < nc; ++j) {
        if (!(EvalPoly4(poly, cand[j]) > 0)) continue;
        const double s = std::clamp(m + 2 * std::atan(cand[j]), 0.0, a.sweep);
        Descend(a, s, best);
      }
    }
  }
}

}  // namespace

LoopWirePieceMin CalcArcCircleMin(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                  const Eigen::Vector3d& e2, double rho, double rho_sq_minus_one,
                                  double sweep, double local_form_above) {
  Arc a;
  a.o = o;
  a.u = rho * e1;
  a.v = rho * e2;
  a.rho = rho;
  a.sweep = sweep;
  a.max_step = std::min(0.5, 0.5 / rho);
  LoopWirePieceMin best;
  best.dist_sq = std::numeric_limits<double>::infinity();
  // The ends, and the descent from the nearer one.
  const Eval e0 = EvalF(a, 0), e1v = EvalF(a, sweep);
  Descend(a, e0.f <= e1v.f ? 0.0 : sweep, &best);
  if (e1v.f < best.dist_sq) best = {e1v.f, sweep, e1v.p, best.iterations, true};
  if (e0.f < best.dist_sq) best = {e0.f, 0.0, e0.p, best.iterations, true};
  // |x(s)|² = |o|² + ρ² + 2(o·u cos s + o·v sin s): least at s_c (the arc point nearest the
  // loop's centre), when s_c lies on the arc.
  const double ou = o.dot(a.u), ov = o.dot(a.v);
  const bool has_nearest_to_centre = ou != 0 || ov != 0;
  const double s_centre = has_nearest_to_centre ? AngleOf(-ou, -ov) : 0;
  int rounds = 0;
  for (; rounds < kLoopWireMaxArcRounds; ++rounds) {
    const double t_sq = best.dist_sq;
    const double before = best.dist_sq;
    if (t_sq >= 1) {
      // Beyond the horn torus: a point with |x|² < t² − 1 is closer than t (d² ≤ |x|² + 1).
      if (has_nearest_to_centre && s_centre <= sweep) {
        const Eval ec = EvalF(a, s_centre);
        if (ec.p.squaredNorm() < t_sq - 1 || ec.f < best.dist_sq) {
          Descend(a, s_centre, &best);
          if (best.dist_sq < before * (1 - kProgressRel)) continue;
        }
      }
    }
    if (std::max(rho, o.norm()) > local_form_above) {
      CertifyWithLocalForms(a, t_sq, &best);
    } else {
      CertifyOnWholeCircle(a, o, e1, e2, rho, rho_sq_minus_one, t_sq, &best);
    }
    if (!(best.dist_sq < before * (1 - kProgressRel))) break;
  }
  best.converged = rounds < kLoopWireMaxArcRounds;
  return best;
}

}  // namespace microdex::geometry
