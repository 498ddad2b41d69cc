#pragma once
// An independent reference for the needle–vessel clearance, for tests only: the needle is
// sampled densely in long double directly from the world poses (no vessel-frame algebra,
// no orthonormality identities), every sampled local maximum of the distance to the core
// circle is refined by golden-section search, and the azimuth-range boundaries are located
// by bisection. Slow (tens of microseconds per query) and simple on purpose.

#include "common/geometry/arc_torus.h"

namespace microdex::geometry::testing {

struct BruteForceClearance {
  ClearanceStatus status = ClearanceStatus::kEmptyRange;
  long double clearance_m = 0;  // r − max distance; meaningful only when kOk
  long double s_rad = 0;        // the needle parameter of that maximum
};

// Valid input assumed. `samples` evenly spaced needle points seed the search.
BruteForceClearance CalcArcTorusClearanceBruteForce(const ArcDef& arc, const TorusSegmentDef& torus,
                                                    int samples = 2048);

// Distance of the needle point at parameter s to the core circle, in long double.
long double BruteForceDistanceToCore(const ArcDef& arc, const TorusSegmentDef& torus,
                                     long double s_rad);

}  // namespace microdex::geometry::testing
