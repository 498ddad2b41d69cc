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

#include <array>
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

struct MeshMap {
  AxisMap x;
  AxisMap y;
  bool Active() const { return x.shift_m != 0 || y.shift_m != 0; }
  std::uint64_t Hash() const;  // identifies the element matrices the map gives
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
