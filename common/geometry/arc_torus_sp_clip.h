#pragma once
// SP stage 1, clip (thesis §4.2.4, last paragraph): the needle circle in the vessel frame and
// the pieces of the arc whose azimuth lies in the segment [0, Ω]. Internal to the SP clearance
// (arc_torus_sp.cc); exposed for its stage tests.

#include <Eigen/Core>

#include "common/geometry/arc_azimuth_clip.h"
#include "common/geometry/arc_torus.h"

namespace microdex::geometry::sp {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2 * kPi;
inline constexpr int kMaxIntervals = kMaxAzimuthPieces;

// A piece [lo, hi] of the needle parameter, with the cosine and sine of its ends.
using Interval = AzimuthPiece;

// The needle circle x(s) = o + ρ(cos s e1 + sin s e2) in the vessel frame V [m].
struct NeedleInV {
  Eigen::Vector3d o, e1, e2, e3;  // e3 = e1 × e2
  double rho = 0, inv_rho = 0;
  Eigen::Vector3d PointAt(double s) const {
    return o + rho * (std::cos(s) * e1 + std::sin(s) * e2);
  }
};

// The needle's circle in the vessel frame V, axes re-orthonormalised (Gram–Schmidt).
NeedleInV MakeNeedleInV(const ArcDef& arc, const TorusSegmentDef& torus);

// cos s and sin s, free at s = 0 (the needle's first point, the usual first piece end).
void CosSin(double s, double* cs, double* sn);

// The pieces of the arc inside the segment (ClipArcToAzimuthRange, arc_azimuth_clip.h).
inline int ClipArcToSegment(const NeedleInV& nv, double sweep, double cos_sweep, double sin_sweep,
                            double omega, Interval out[kMaxIntervals]) {
  return ClipArcToAzimuthRange(nv.o, nv.e1, nv.e2, nv.rho, sweep, cos_sweep, sin_sweep, omega, out);
}

// The piece that holds s (snapped across rounding at the ends, and across 2π), or −1.
int FindInterval(const Interval* iv, int n, double s);

}  // namespace microdex::geometry::sp
