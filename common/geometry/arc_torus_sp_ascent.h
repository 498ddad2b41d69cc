#pragma once
// SP stage 4, refine: the extrema of G are not those of the distance, so the clearance is
// taken at the end of a safeguarded Newton ascent of the distance² to the core circle from
// starting points (piece ends, SP minima, certificate points). Internal to the SP clearance
// (arc_torus_sp.cc); exposed for its stage tests.

#include <cmath>

#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/arc_torus_sp_clip.h"

namespace microdex::geometry::sp {

// Largest step of the distance ascent [rad of needle parameter].
inline constexpr double kMaxPolishStep_rad = 0.5;
// Distances within this fraction of R of the core radius count as beyond the horn torus (the
// deep-contact threshold: level sets there are spindle tori).
inline constexpr double kDeepRel = 1e-6;

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

// (cos, sin) of s_new = s + h from those of s, without libm for |h| ≤ kMaxPolishStep_rad.
void AdvanceAngle(double s_new, double h, double* cs, double* sn);

// Safeguarded Newton ascent of the distance² on [iv.lo, iv.hi] from *s (cos = *cs, sin = *sn,
// values *cur there), at most polish_max_iters steps: the Newton step where f is concave, a
// bounded step uphill elsewhere, halved until f does not decrease. Moves (*s, *cs, *sn, *cur)
// to the best point; returns false when the step budget ran out before convergence.
bool AscendCoreDistSq(const NeedleInV& nv, double core_radius, const Interval& iv,
                      const SpOptions& opt, double* s_io, double* cs_io, double* sn_io,
                      CoreDistSq* cur_io);

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

inline Candidate MakeCandidate(const NeedleInV& nv, double core_r, double s, double cs, double sn,
                               int interval, CandidateKind kind) {
  const CoreDistSq e = EvalCoreDistSq(nv, core_r, cs, sn);
  return {s, cs, sn, interval, kind, e.f, e.df, e.d2f};
}
// The deep-contact threshold: see kDeepRel.
inline bool IsDeep(double f, double core_r) {
  return f >= (1 - kDeepRel) * (1 - kDeepRel) * core_r * core_r;
}

// The deepest point found so far: the needle parameter of the largest distance² to the core.
struct Best {
  double f = -1, s = 0, cos_s = 1, sin_s = 0;
};

// The piece ends of every interval as starting points; returns whether one is beyond the horn
// torus (IsDeep).
bool AddPieceEnds(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv, Candidate* cand,
                  int* n_cand);

// Distance ascent from one candidate (several budgets of polish_max_iters steps if it has not
// converged), keeping the best point in *best. Returns the f it reached.
double TryCandidate(const NeedleInV& nv, double core_r, const Interval* iv, const Candidate& c,
                    const SpOptions& opt, Best* best);

}  // namespace microdex::geometry::sp
