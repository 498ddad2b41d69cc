#pragma once
// The exact needle–vessel clearance: the accuracy reference for the other methods and the
// value that drives the cues. See README.md "Exact method" for the derivation.
//
// In the vessel frame, scaled so that R = 1, the squared distance of the needle point p(s)
// to the core circle is F(s) = (k − 1)² + z², k = |p_xy|. Its critical points are the roots
// of Φ(s) = kA − B (A = p·p', B = p_xy·p'_xy), a subset of the roots of the degree-4
// trigonometric polynomial P = hA² − B² = eA² + zz'(A + B) (h = k², e = h − 1), whose
// coefficients are formed from the input so that they are accurate relative to their own
// size in the degenerate families (needle on the core circle, coaxial circles, coplanar).
// P is isolated on each clipped parameter interval by Descartes' rule on its Bernstein form
// (after the half-angle substitution) with rounding-aware signs; the maximum of the
// distance is taken over the interval ends, the roots of P and, where P cannot be resolved
// from rounding (double roots: the needle through the z axis, symmetric poses), over the
// sign changes of Φ found by bisection.
//
// Hot path: no allocation, no exception; invalid input returns kInvalidInput.

#include "common/geometry/arc_torus.h"

namespace microdex::geometry {

// Work counters of one query, for tests and the benchmark.
struct ExactDiagnostics {
  int num_intervals = 0;    // pieces of the arc inside the azimuth range
  int num_nodes = 0;        // Bernstein subdivision nodes visited
  int num_roots = 0;        // isolated simple roots of P
  int num_fuzzy = 0;        // nodes left unresolved by rounding, settled through Φ
  int num_local_forms = 0;  // nodes re-expanded about a local needle point
  bool node_budget_hit = false;
};

ArcTorusClearance CalcArcTorusClearanceExact(const ArcDef& arc, const TorusSegmentDef& torus);
ArcTorusClearance CalcArcTorusClearanceExact(const ArcDef& arc, const TorusSegmentDef& torus,
                                             ExactDiagnostics* diagnostics);

// The clearance result for the needle point at parameter s (already known to be inside the
// azimuth range): closest points in world. Shared by the sampled and exact methods.
ArcTorusClearance MakeArcTorusClearance(const TorusSegmentDef& torus, const ArcInTorusFrame& frame,
                                        double s_rad, double cos_s, double sin_s,
                                        double distance_to_core_m);

}  // namespace microdex::geometry
