#pragma once
// A turning piece of the wire against the loop's core circle: the exact minimum distance from
// a circular arc to a circle, by descent and the level-torus certificate of the needle–vessel
// query turned round (README.md, "Loop along a wire", "Arcs").
//
// In the loop frame with lengths in units of R, x(s) = o + ρ(cos s e₁ + sin s e₂),
// s ∈ [0, S]. The best point starts at the nearer end and moves by a safeguarded Newton
// descent of F(s) = distance² to the core circle. Then the certificate (the same lifted level
// torus as the SP query's, arc_torus_sp.h CalcLevelTorusAlongNeedle): the points of the arc
// closer than t = √F_best are those where G̃_t(s) = −(d² − t²)(D² − t²) > 0 (d, D: distances
// to the nearest and the farthest point of the core circle; D ≥ R > t below the horn torus);
// G̃_t is a trigonometric polynomial of degree 2 in s, whose extrema are the roots of the
// quartic (4.26) (FindConicExtremaOnCircle). None positive inside the arc: no point closer,
// the best point is the minimum. Otherwise the descent restarts there, strictly lower; each
// round reaches another local minimum, of which there are at most four. Beyond the horn torus
// (t ≥ R) the lemon where D < t lies inside the ball |x|² < t² − R², whose points are all
// closer than t: the arc's point nearest the centre is tested first. For arcs of radius or
// centre distance beyond kLoopWireLocalFormAbove, the level torus is expanded about points of
// the arc inside the ball |x| ≤ t + R instead (local forms, README.md).
//
// No allocation, no exception.

#include <Eigen/Core>

#include "common/geometry/loop_wire_segment.h"

namespace microdex::geometry {

// Certificate rounds before the arc query gives up (LoopWirePieceMin::converged = false).
inline constexpr int kLoopWireMaxArcRounds = 12;
// Above this radius or centre distance (units of R) the certificate uses local forms of the
// level torus about points of the arc instead of the whole-circle form, whose coefficients
// (of the size of ρ⁴ and |o|⁴) cancel down to the values near the loop: on arcs of radius
// ≥ 10 R the whole-circle quartic no longer resolves the level torus's small extrema there
// (0.57 R off at ρ = 2000 R).
inline constexpr double kLoopWireLocalFormAbove = 4;

// The arc o + rho (cos s e1 + sin s e2), s ∈ [0, sweep] (loop frame, units of R; e1, e2
// orthonormal, rho > 0, sweep ∈ (0, 2π]); rho_sq_minus_one = ρ² − 1 formed by the caller as
// accurately as its inputs allow.
LoopWirePieceMin CalcArcCircleMin(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                  const Eigen::Vector3d& e2, double rho, double rho_sq_minus_one,
                                  double sweep, double local_form_above = kLoopWireLocalFormAbove);

}  // namespace microdex::geometry
