#pragma once
// The tool's prescribed displacement imposed where the tool really is: penalty springs at
// points attached to the tool (its own arc-length coordinate, not the grid), each acting on
// the mesh through the shape functions of the triangle that contains it. The system then
// depends continuously on the tool's pose for a given mesh: a point that crosses an edge
// changes triangle, but the shape functions of the shared edge's nodes agree on the edge and
// the third one vanishes there. Points are spaced like the local cells (one per cell along
// the tool, denser in the end zones), so that they constrain no more values than the mesh has
// beside the line (no locking: see README, "Tool constraint").

#include <array>
#include <cstdint>
#include <span>

#include "common/fem/multiscale_mesh.h"
#include "common/fem/tissue_model.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {

// One penalty point of the tool: where it is, the prescribed displacement there and the
// triangle of the step's mesh that holds it.
struct ToolPoint {
  double x_m = 0;
  double y_m = 0;
  double u_m = 0;    // prescribed displacement (the tool's height), m
  double dir_x = 0;  // unit direction of the tool's segment in the plane
  double dir_y = 0;
  double length_m = 0;                 // the share of the tool this point stands for
  std::array<std::int32_t, 3> node{};  // grid nodes of the containing triangle
  std::array<double, 3> lambda{};      // barycentric coordinates of the point in it
  // Σ λ_a |d_a|, d_a the distance of node a to the tool's line: how far the P1 interpolant of
  // the kinked field w = U + s|d| sits from U at the point (LocateToolPoint).
  double kink_m = 0;
  double spring_N_per_m = 0;  // the point's penalty spring (ToolPointSpring)
};

// The spring that makes a point consistent with the kink of the field across the tool line:
// the line load q = 2 G t s holds w = U + s|d| on both sides, whose P1 interpolant is
// U + s·kink at the point, so a spring k = 2 G t · length / kink carries the point's share of
// the load q·length exactly when the mesh lags the tool by the interpolation error; times
// kink_factor (TissueDef::tool_kink_factor). Capped at cap_N_per_m (a point on the mesh's
// edges: kink → 0, where w = U is exact).
double ToolPointSpring(const ToolPoint& point, double shear_modulus_Pa, double thickness_m,
                       double kink_factor, double cap_N_per_m);

// The points of the tool's pressed parts (z < 0) strictly inside the domain, along each
// segment: both ends, spacing `spacing · h` (h the cell size of `level`) along the segment and
// `spacing · h_end` within grading · h of a vertex that is an end zone of the mesh. The
// positions depend only on the tool (its vertices and length), never on the mesh, so a rigid
// tool carries its points with it. Returns the number written, or −1 when `out` is too small.
int PlaceToolPoints(const TissueModel& model, const EndZones& zones, int level,
                    const ToolContact& tool, double spacing, std::span<ToolPoint> out);

// Finds the triangle of the mesh that contains (x, y) (a point on the tool: its leaf is at
// the level LeafLevelOnTool gives) and writes its nodes and the barycentric coordinates.
void LocateToolPoint(const TissueModel& model, const MeshSelection& mesh, const ToolContact& tool,
                     ToolPoint& point);

}  // namespace microdex::fem
