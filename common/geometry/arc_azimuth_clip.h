#pragma once
// The part of the needle inside the vessel segment's azimuth range [0, Ω] (thesis §4.2.4,
// last paragraph): the needle parameter interval [0, S] cut where the arc crosses the two
// half-planes bounding the segment (azimuth 0 and azimuth Ω, both containing the z axis).

#include <Eigen/Core>

#include "common/geometry/arc_torus.h"

namespace microdex::geometry {

// At most: each bounding plane cuts a circle twice, so [0, S] has at most 5 pieces, of
// which at most 3 alternate inside.
inline constexpr int kMaxAzimuthIntervals = 3;
inline constexpr int kMaxAzimuthPieces = kMaxAzimuthIntervals;

// A piece [lo, hi] of the needle parameter inside the range, with the cosine and sine of its
// ends.
struct AzimuthPiece {
  double lo = 0, hi = 0;
  double cos_lo = 1, sin_lo = 0, cos_hi = 1, sin_hi = 0;
};

// s ∈ (−4π, 4π) (atan2 and acos sums) to [0, 2π).
double WrapTo2Pi(double s);

// The pieces of the arc x(s) = o + ρ(cos s e1 + sin s e2), s ∈ [0, sweep] (cos_sweep and
// sin_sweep its end's), whose azimuth lies in [0, omega], in order of s, merged where they
// touch; returns their count (0: no needle point in the range). The arc crosses the boundary
// half-planes (azimuth 0 and Ω) where it crosses their planes through the z axis,
// A cos s + B sin s + C = 0; between consecutive crossings the azimuth test of one point
// decides the whole piece. Every piece end carries its (cos s, sin s), from the same algebra
// as s itself, so that neither the test points nor the piece ends need libm. Any length unit.
// The one clipping of the project: SP's first stage, the exact method and the clipped sampler.
int ClipArcToAzimuthRange(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                          const Eigen::Vector3d& e2, double rho, double sweep, double cos_sweep,
                          double sin_sweep, double omega, AzimuthPiece out[kMaxAzimuthPieces]);

struct AzimuthIntervals {
  int count = 0;
  double begin[kMaxAzimuthIntervals] = {};  // needle parameter s, rad, sorted
  double end[kMaxAzimuthIntervals] = {};    // begin ≤ end
};

// ClipArcToAzimuthRange of the arc in the torus frame, without the pieces' cosines and sines.
// Isolated points (the arc grazing a bounding plane from outside) are dropped.
AzimuthIntervals CalcAzimuthIntervals(const ArcInTorusFrame& arc, double segment_angle_rad);

// The start of every query restricted to the azimuth range (the exact method and the clipped
// sampler): checks the input, puts the arc in the torus frame and clips it. Returns false when
// there is nothing to solve, with out.status kInvalidInput or kEmptyRange; out.clearance_m is
// NaN either way.
bool StartClippedQuery(const ArcDef& arc, const TorusSegmentDef& torus, ArcInTorusFrame& frame,
                       AzimuthIntervals& intervals, ArcTorusClearance& out);

}  // namespace microdex::geometry
