#pragma once
// The part of the needle inside the vessel segment's azimuth range [0, Ω] (thesis §4.2.4,
// last paragraph): the needle parameter interval [0, S] cut where the arc crosses the two
// half-planes bounding the segment (azimuth 0 and azimuth Ω, both containing the z axis).

#include "common/geometry/arc_torus.h"

namespace microdex::geometry {

// At most: each bounding plane cuts a circle twice, so [0, S] has at most 5 pieces, of
// which at most 3 alternate inside.
inline constexpr int kMaxAzimuthIntervals = 3;

struct AzimuthIntervals {
  int count = 0;
  double begin[kMaxAzimuthIntervals] = {};  // needle parameter s, rad, sorted
  double end[kMaxAzimuthIntervals] = {};    // begin ≤ end
};

// Maximal sub-intervals of [0, arc.sweep] whose points have their azimuth in [0, Ω]
// (IsAzimuthInSegment). Each piece between consecutive crossings is classified at its
// midpoint, so the result is consistent even where crossings are computed inexactly.
// Isolated points (the arc grazing a bounding plane from outside) are dropped.
AzimuthIntervals CalcAzimuthIntervals(const ArcInTorusFrame& arc, double segment_angle_rad);

}  // namespace microdex::geometry
