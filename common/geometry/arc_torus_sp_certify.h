#pragma once
// SP stage 5, certify (README_sp.md, "Certificate"): the level set {distance = t} through the
// deepest point found is a torus of tube radius t; a point farther than t exists only where
// the lifted level torus is negative. First a quick test on the lifted torus along the needle
// (no quartic); where it cannot prove, a full SP pass against the level torus (stages 2–3);
// beyond the horn torus (t ≥ R) an extrema search along the needle. Internal to the SP
// clearance (arc_torus_sp.cc); exposed for its stage tests. (CalcLevelTorusAlongNeedle,
// declared in arc_torus_sp.h, is defined with this stage.)

#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/arc_torus_sp_ascent.h"
#include "common/geometry/arc_torus_sp_clip.h"

namespace microdex::geometry::sp {

// Below this fraction of R the level torus is too thin for the lifted conic's precision (the
// clearance is then within this of r).
inline constexpr double kMinCertifyRel = 1e-6;

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

// Proves G̃_t ≥ −eps on every piece from the polynomial q = G̃_t along the needle rotated to
// the deepest point s_best (cos ca, sin sa): true proves that no needle point is farther
// than t (beyond the horn torus, outside the lemon that `outer` excludes). Only sufficient.
bool ProveNoFartherPoint(const CircleConic& q, const Interval* iv, int n_iv, double s_best,
                         double ca, double sa, double eps, const LevelOuterSide* outer);

// The certificate's extrema search on G̃_t along the needle (README_sp.md, "Deep contacts"):
// the extrema below −eps inside the pieces and outside the lemon are appended to starts (none:
// no farther point). Returns false when G̃_t is constant along the needle.
bool FindLevelMinimaAlongNeedle(const NeedleInV& nv, double core_r, const CircleConic& g,
                                double eps, const LevelOuterSide* outer, const Interval* iv,
                                int n_iv, const SpOptions& opt, Candidate* starts, int* n_start);

// Precondition of both rounds below: no piece end is farther from the core circle than
// *best (the query starts its ascent from the farthest end), so a farther point, if any, is
// inside a piece, where the level torus's conic has a minimum below zero.

// What one certificate round concluded.
enum class CertifyStep {
  kProved,             // no needle point farther than the best: best is the deepest point
  kProvedAlongNeedle,  // the same, beyond the horn torus, by the extrema along the needle
  kImproved,           // a farther point was found and ascended to: *best moved
  kNeedsLiftedPass,    // the quick test could not decide (QuickCertify only)
};

// The quick test at the level t² = max(best f, (kMinCertifyRel R)²) and, beyond the horn
// torus, the extrema search along the needle.
CertifyStep QuickCertify(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                         const SpOptions& opt, Best* best);

// A full SP pass (stages 2–3) against the level torus at the same level, its minima (or, when
// the lifted circle is unusable, uniform points: *uniform_fallback) ascended. Not beyond the
// horn torus (IsDeep(best->f)): the caller falls back first.
CertifyStep LiftedCertify(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                          const SpOptions& opt, Best* best, bool* uniform_fallback);

}  // namespace microdex::geometry::sp
