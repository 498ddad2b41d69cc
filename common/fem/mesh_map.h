#pragma once
// The mesh attached to the tissue under the tool (TissueDef::attached_mesh). While a tool
// presses, the multi-scale mesh is chosen in a reference plane in which the tool does not
// translate, and its nodes are placed in the tissue plane by a map that carries the tool's
// neighbourhood rigidly with the tool and stretches the rest of the patch to fit its clamped
// edges. A tool sliding over the patch then keeps its mesh, its tool points and their
// triangles: the discretisation near the tool does not change, and the force is a smooth
// function of the motion instead of following the tool's place relative to the grid lines
// (the ripple and the mesh-change steps of common/fem/README.md, "Continuity").
//
// The map is separable and piecewise linear on each axis: the reference interval [lo, hi]
// around the tool is shifted by the tool's motion since contact began, [0, lo] and [hi, L]
// are stretched or squeezed to keep 0 and L in place. Every cell stays a rectangle, every
// template triangle a right triangle (scaled per axis), so the element matrices stay those of
// the templates: K = (s_y / s_x) K_xx + (s_x / s_y) K_yy.
//
// A turning tool is absorbed by a twist about the anchor's centroid, applied before the axis
// maps: the disc of radius r₁ (the box's inscribed disc) turns rigidly with the tool, the
// annulus out to r₂ (the nearest edge of the patch) by θ ln(r₂/r) / ln(r₂/r₁), the profile of
// least shear (its shear r dφ/dr = θ / ln(r₂/r₁) is the same everywhere in the annulus), and
// nothing beyond. Distances to the centre are kept, so the inverse is the twist turned back.
// The element matrix is invariant under a rotation, so the disc's triangles keep their
// templates; the annulus's triangles are computed from their mapped vertices.

#include <array>
#include <cmath>
#include <cstdint>

#include "common/fem/tissue_model.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {

// One axis: reference [0, lo] → [0, lo + shift], [lo, hi] → [lo + shift, hi + shift],
// [hi, L] → [hi + shift, L], each linear. Shift 0 (the default): the identity.
struct AxisMap {
  double lo_m = 0;
  double hi_m = 0;
  double length_m = 0;
  double shift_m = 0;

  double ToPhysical(double r_m) const {
    if (shift_m == 0) return r_m;
    if (r_m < lo_m) return r_m * (lo_m + shift_m) / lo_m;
    if (r_m <= hi_m) return r_m + shift_m;
    return hi_m + shift_m + (r_m - hi_m) * (length_m - hi_m - shift_m) / (length_m - hi_m);
  }
  double ToReference(double p_m) const {
    if (shift_m == 0) return p_m;
    if (p_m < lo_m + shift_m) return p_m * lo_m / (lo_m + shift_m);
    if (p_m <= hi_m + shift_m) return p_m - shift_m;
    return hi_m + (p_m - hi_m - shift_m) * (length_m - hi_m) / (length_m - hi_m - shift_m);
  }
  // d(physical)/d(reference) on the piece holding [r0, r1], or −1 when the interval spans a
  // breakpoint (its triangles are then computed from their mapped vertices).
  double Slope(double r0_m, double r1_m) const {
    if (shift_m == 0) return 1;
    if (r1_m <= lo_m) return (lo_m + shift_m) / lo_m;
    if (r0_m >= lo_m && r1_m <= hi_m) return 1;
    if (r0_m >= hi_m) return (length_m - hi_m - shift_m) / (length_m - hi_m);
    return -1;
  }
};

// The twist about (cx, cy): rigid within r₁, a log profile out to r₂, the identity beyond.
// Turn 0 (the default): the identity.
struct TwistMap {
  double cx_m = 0;
  double cy_m = 0;
  double r1_m = 0;
  double r2_m = 0;
  double turn_rad = 0;

  // The angle by which a point at distance r turns.
  double Angle(double r_m) const {
    if (r_m <= r1_m) return turn_rad;
    if (r_m >= r2_m) return 0;
    return turn_rad * std::log(r2_m / r_m) / std::log(r2_m / r1_m);
  }
  void Turn(double sign, double* x_m, double* y_m) const {
    if (turn_rad == 0) return;
    const double dx = *x_m - cx_m, dy = *y_m - cy_m;
    const double a = sign * Angle(std::sqrt(dx * dx + dy * dy));
    const double c = std::cos(a), s = std::sin(a);
    *x_m = cx_m + c * dx - s * dy;
    *y_m = cy_m + s * dx + c * dy;
  }
  // How the reference rectangle [x0, x1] × [y0, y1] is moved: 0 not at all (outside r₂),
  // 1 rigidly (inside r₁), 2 sheared (it meets the annulus).
  int Classify(double x0, double x1, double y0, double y1) const;
};

struct MeshMap {
  AxisMap x;
  AxisMap y;
  TwistMap twist;
  bool Active() const { return x.shift_m != 0 || y.shift_m != 0 || twist.turn_rad != 0; }
  std::uint64_t Hash() const;  // identifies the element matrices the map gives

  // Reference → tissue plane: the twist, then the axes.
  void ToPhysical(double rx_m, double ry_m, double* px_m, double* py_m) const {
    twist.Turn(1, &rx_m, &ry_m);
    *px_m = x.ToPhysical(rx_m);
    *py_m = y.ToPhysical(ry_m);
  }
  void ToReference(double px_m, double py_m, double* rx_m, double* ry_m) const {
    *rx_m = x.ToReference(px_m);
    *ry_m = y.ToReference(py_m);
    twist.Turn(-1, rx_m, ry_m);
  }
  // A box in the tissue plane that holds the image of the reference rectangle.
  void ImageBox(double x0, double x1, double y0, double y1, double* px0, double* px1, double* py0,
                double* py1) const;
};

// Where and how the mesh was attached: the tool's centroid at the first step of contact and
// the reference box carried with it. State (TissueState::mesh_anchor): the map of a step is a
// function of this and the tool.
struct MeshAnchor {
  bool valid = false;
  double cx_m = 0;  // the tool's planar centroid when attached
  double cy_m = 0;
  double x_lo_m = 0;  // the reference box [x_lo, x_hi] × [y_lo, y_hi] moved rigidly
  double x_hi_m = 0;
  double y_lo_m = 0;
  double y_hi_m = 0;
  bool slide_x = false;  // false: the axis keeps the identity (the box too close to an edge)
  bool slide_y = false;
  // The twist's radii about (cx, cy); r2 = 0: the tool's turn is not absorbed (the patch's edge
  // is too near for a twist of useful reach).
  double twist_r1_m = 0;
  double twist_r2_m = 0;
  // The tool's planar vertices when attached. A vertex mapped back to within
  // kReferenceSnap_m of its attached place is taken at that place exactly, so that a tool
  // translating rigidly has bit for bit the same reference geometry every step (the rounding of
  // p − shift would otherwise flip the mesh's refinement tests of a tool on a grid line).
  int num_points = 0;
  std::array<double, kMaxToolPoints> x_m{};
  std::array<double, kMaxToolPoints> y_m{};
};

inline constexpr double kReferenceSnap_m = 1e-12;

// Squeezing or stretching a side of the patch beyond this factor attaches the mesh afresh.
inline constexpr double kMaxMeshStretch = 4.0;
// The box carried rigidly with the tool: the tool's disc plus this many nominal cells.
inline constexpr double kMeshBoxMarginCells = 1.5;
// The twist's shear r dφ/dr at most this: a right triangle's vertices then move relative to one
// another by less than the 1/√2 of its size at which it could fold.
inline constexpr double kMaxTwistShear = 0.65;
// And its turn at most this (the chords of a large turn would shorten the sheared edges).
inline constexpr double kMaxTwist_rad = 0.6;
// A twist needs r₂ ≥ this × r₁ (with less room its turn before attaching afresh is too small).
inline constexpr double kMinTwistReach = 1.5;

// The map for this tool: from the anchor when it holds the tool (the tool's box in the
// reference inside the anchor's, neither side of an axis squeezed or stretched by more than
// kMaxMeshStretch); otherwise the anchor is made afresh at the tool (*reattached = true) and
// the map is the identity. The box is the disc around the centroid that holds every vertex,
// plus kMeshBoxMarginCells cells of the nominal level, so a tool turning about its centroid
// stays in it.
MeshMap AttachMesh(const TissueModel& model, const ToolContact& tool, MeshAnchor& anchor,
                   bool* reattached);

// The tool in the reference plane (vertices and torque point mapped back; vertices snapped
// to the anchor's, see MeshAnchor).
ToolContact ToReference(const MeshMap& map, const MeshAnchor& anchor, const ToolContact& tool);

}  // namespace microdex::fem
