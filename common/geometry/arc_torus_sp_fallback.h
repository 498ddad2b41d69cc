#pragma once
// SP stage 6, fall back: where the lifted circle is too ill-conditioned (or φ is constant on
// it) the ascent starts from uniform points of each piece instead of SP's minima; where the
// deepest point lies beyond the horn torus and the certificate's error bound fails, the exact
// method (arc_torus_exact.h) answers. Internal to the SP clearance (arc_torus_sp.cc); exposed
// for its stage tests.

#include "common/geometry/arc_torus.h"
#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/arc_torus_sp_ascent.h"
#include "common/geometry/arc_torus_sp_clip.h"

namespace microdex::geometry::sp {

// Uniform starting points per in-range piece on the robust path.
inline constexpr int kRobustSamples = 24;
// Room for every starting point of one query: piece ends, SP minima, uniform points.
inline constexpr int kMaxCandidates = 16 + kMaxIntervals * (kRobustSamples + 2);

// kRobustSamples interior points of each piece, evenly spaced, appended to cand.
void AddUniformCandidates(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                          Candidate* cand, int* n_cand);

// The exact method's answer, recorded as the deep fallback in *diag.
ArcTorusClearance FallBackToExact(const ArcDef& arc, const TorusSegmentDef& torus,
                                  SpDiagnostics* diag);

}  // namespace microdex::geometry::sp
