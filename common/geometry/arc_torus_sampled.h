#pragma once
// Baseline (thesis Fig. 4.3b): the needle sampled at N evenly spaced points, the clearance
// taken as the minimum of r − distance(point, core circle) over the samples inside the
// segment's azimuth range. Its error falls like the square of the spacing (a smooth
// maximum of the distance between two samples) and its cost grows like N.

#include "common/geometry/arc_torus.h"

namespace microdex::geometry {

// samples ≥ 2 (fewer is treated as 2): s_i = S i / (N − 1), i = 0 … N − 1. kEmptyRange
// when no sample is inside the azimuth range. No allocation.
ArcTorusClearance CalcArcTorusClearanceSampled(const ArcDef& arc, const TorusSegmentDef& torus,
                                               int samples);

// The same budget spread over the needle's pieces inside the azimuth range
// (arc_azimuth_clip.h), each sampled evenly with both ends: a deepest point on a segment's end
// plane is then sampled exactly, and the error keeps falling like the spacing squared where
// the plain version's falls like the spacing (a boundary missed by up to S/N). No azimuth test
// per sample. samples ≥ 2 per piece. No allocation.
ArcTorusClearance CalcArcTorusClearanceSampledClipped(const ArcDef& arc,
                                                      const TorusSegmentDef& torus, int samples);

}  // namespace microdex::geometry
