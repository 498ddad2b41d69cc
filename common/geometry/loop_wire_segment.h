#pragma once
// A straight piece of the wire against the loop's core circle: the exact minimum distance from
// a segment to a circle (README.md, "Loop along a wire", "Straight pieces").
//
// In the loop frame with lengths in units of R (the core circle: radius 1 around the origin
// in z = 0). With the segment written about the point p_c of its line nearest to the origin,
// p(τ) = p_c + τ d (|d| = 1, p_c·d = 0), the squared distance to the circle is
// F(τ) = (k − 1)² + z², k = |p_xy|, and F'(τ)/2 = G(τ) = τ − (p_xy·d_xy)/k: a line minus a
// sigmoid, (p_xy·d_xy)/k = α(τ − τ₀)/√(α(τ − τ₀)² + b²) (α = |d_xy|², b the line's distance
// from the z axis). G' = 1 − αb²/k³ changes sign at most twice, at k³ = αb², so [τ_lo, τ_hi]
// splits into at most three pieces on which G is monotone; the minima of F are the roots of G
// on the increasing ones (at most two), each bracketed and found by safeguarded Newton. No
// squaring: the quartic of the stationary points (τk = p_xy·d_xy squared) has double roots
// where the wire lies in the loop's plane, and spurious ones; this form has neither.
//
// No allocation, no exception.

#include <Eigen/Core>
#include <cmath>

namespace microdex::geometry {

struct LoopWirePieceMin {
  double dist_sq = 0;  // minimum squared distance to the core circle (units of R²)
  double param = 0;    // segment: arc length from its first end (units of R); arc: s (rad)
  Eigen::Vector3d p = Eigen::Vector3d::Zero();  // the nearest piece point (loop frame, R units)
  int iterations = 0;                           // Newton/bisection steps, or certificate rounds
  bool converged = true;
};

// The segment from a to b (loop frame, units of R; a ≠ b).
LoopWirePieceMin CalcSegmentCircleMin(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// The stationary-point quartic of the same problem, for comparison (tests, benchmark): with
// τ measured from p_c as above, the roots of τ²k(τ)² − (p_xy·d_xy)² = 0 in [τ_lo, τ_hi],
// solved by quartic.h (closed form, checked, bracketed fallback) and the minimum of F over
// them and the ends.
LoopWirePieceMin CalcSegmentCircleMinQuartic(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// F = (k − 1)² + z² at p (units of R): the squared distance of p to the unit core circle.
inline double CircleDistSq(const Eigen::Vector3d& p) {
  const double k = std::sqrt(p.x() * p.x() + p.y() * p.y());
  return (k - 1) * (k - 1) + p.z() * p.z();
}

}  // namespace microdex::geometry
