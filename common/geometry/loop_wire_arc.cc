#include "common/geometry/loop_wire_arc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/geometry/arc_torus_sp.h"

namespace microdex::geometry {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr int kMaxDescentIters = 100;
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

}  // namespace

LoopWirePieceMin CalcArcCircleMin(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                  const Eigen::Vector3d& e2, double rho, double rho_sq_minus_one,
                                  double sweep) {
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
  SpOptions opt;
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
    double size = 0;
    const CircleConic q = CalcLevelTorusAlongNeedle(o, e1, e2, rho, rho_sq_minus_one, t_sq, &size);
    double ct[8], st[8];
    bool constant = false;
    const int n = FindConicExtremaOnCircle(q, opt, ct, st, &constant);
    for (int j = 0; j < n; ++j) {
      if (!(q.Eval(ct[j], st[j]) > 0)) continue;
      const double s = AngleOf(ct[j], st[j]);
      if (s > sweep) continue;
      Descend(a, s, &best);
    }
    if (!(best.dist_sq < before * (1 - kProgressRel))) break;
  }
  best.converged = rounds < kLoopWireMaxArcRounds;
  return best;
}

}  // namespace microdex::geometry
