#pragma once
// The needle–vessel query (thesis chapter 4): a suture needle, a circular arc, against a
// vessel, a segment of a torus. Every method (SP, exact, sampled, mesh) answers the same
// question with the same types, so the station, the cues and the benchmark can swap them.
//
// Clearance: the minimum, over the needle points whose azimuth in the
// tube frame lies in [0, segment_angle], of r − distance(point, core circle). Positive: the
// needle is inside the tube by that margin; ≤ 0: it touches or crosses the wall.

#include <Eigen/Geometry>
#include <string>

namespace microdex::geometry {

// The needle. In its frame N it is the arc (ρ cos s, ρ sin s, 0), s ∈ [0, sweep].
struct ArcDef {
  double radius_m = 1e-3;                                  // ρ > 0
  double sweep_rad = 3.14159265358979323846 / 2;           // S ∈ (0, 2π]
  Eigen::Isometry3d X_WN = Eigen::Isometry3d::Identity();  // needle frame in world
};

// The vessel. In its frame V the core circle has radius R in the xy-plane around the
// origin; the tube radius is r; the segment keeps azimuth atan2(y, x) ∈ [0, Ω].
struct TorusSegmentDef {
  double core_radius_m = 5e-3;                             // R > 0
  double tube_radius_m = 0.5e-3;                           // 0 < r < R
  double segment_angle_rad = 2 * 3.14159265358979323846;   // Ω ∈ (0, 2π]
  Eigen::Isometry3d X_WV = Eigen::Isometry3d::Identity();  // vessel frame in world
};

enum class ClearanceStatus {
  kOk,            // clearance and closest points are valid
  kEmptyRange,    // no needle point lies inside the segment's azimuth range
  kInvalidInput,  // NaN/Inf, non-positive radii, r ≥ R, sweep or Ω outside (0, 2π]
};

struct ArcTorusClearance {
  ClearanceStatus status = ClearanceStatus::kInvalidInput;
  double clearance_m = 0;  // NaN unless status == kOk
  bool contact = false;    // clearance_m ≤ 0 (false unless kOk)
  double s_rad = 0;        // needle parameter of the deepest point (argmin of clearance)
  Eigen::Vector3d p_WD = Eigen::Vector3d::Zero();  // that needle point D (deepest), in world
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();  // B: the tube-wall point nearest to D, in world
};

// The Defs' contract (README "Errors"): throws std::invalid_argument whose message starts with
// the field ("ArcDef.radius_m: expected ..."); the pair is validated together because some
// limits relate the two (the needle's scale and distance against the vessel's).
void ValidateArcTorus(const ArcDef& arc, const TorusSegmentDef& torus);

// The same check without allocation, for the per-query hot path: nullptr when valid,
// otherwise a static one-line reason naming the field.
const char* FindArcTorusInputError(const ArcDef& arc, const TorusSegmentDef& torus);

// The needle expressed in the vessel frame V with every length divided by the core radius
// R (the scene scale), so that the methods work on numbers of order one whatever the units:
// p(s) = center + radius (u cos s + v sin s), s ∈ [0, sweep], core circle of radius 1.
struct ArcInTorusFrame {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();  // unit, the direction of s = 0
  Eigen::Vector3d v = Eigen::Vector3d::UnitY();  // unit, ⊥ u
  double radius = 1;                             // ρ / R
  double radius_minus_one = 0;  // (ρ − R) / R, formed before the division (no cancellation)
  double sweep = 0;             // S, rad
};

// Valid input assumed (FindArcTorusInputError == nullptr).
ArcInTorusFrame CalcArcInTorusFrame(const ArcDef& arc, const TorusSegmentDef& torus);

// Whether the azimuth atan2(y, x) ∈ (−π, π], taken in [0, 2π), of the vessel-frame point
// (x, y, ·) lies in [0, Ω]; Ω ≥ 2π keeps everything. Points on the z axis (atan2(0, 0) = 0)
// are inside. Every method uses this one definition.
bool IsAzimuthInSegment(double x, double y, double segment_angle_rad);

}  // namespace microdex::geometry
