#pragma once
// The tool as seen by the tissue: a point, a line segment (the thesis's "bar") or a polyline
// in the tissue frame S (x, y in the tissue plane, z up, tissue surface at rest at z = 0).
// Where the tool is below the surface it prescribes the displacement of the grid nodes it
// covers (the U_i of (3.7)).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>

namespace microdex::fem {

inline constexpr int kMaxToolPoints = 16;

struct ToolContact {
  int num_points = 0;                                  // 1: point tool; 2: bar; more: polyline
  std::array<Eigen::Vector3d, kMaxToolPoints> p_SP{};  // polyline vertices in S, m
  // Nodes within this distance of the polyline are in contact as well. A finite radius
  // regularises the point tool, whose force on a point contact vanishes as the mesh is refined.
  double contact_radius_m = 0;
  Eigen::Vector3d p_ST = Eigen::Vector3d::Zero();  // point the torque on the tool is taken about
};

ToolContact MakePointTool(const Eigen::Vector3d& p_SP, double contact_radius_m);
ToolContact MakeBarTool(const Eigen::Vector3d& p_SA, const Eigen::Vector3d& p_SB);
// Throws std::invalid_argument when there are no points or more than kMaxToolPoints.
ToolContact MakePolylineTool(std::span<const Eigen::Vector3d> p_SP, double contact_radius_m);

// Distance in the plane from the axis-aligned box [x0, x1] × [y0, y1] to the tool polyline.
double ToolBoxDistance_m(const ToolContact& tool, double x0_m, double y0_m, double x1_m,
                         double y1_m);

// Closest point of the tool polyline to (x, y) in the plane: returns the planar distance and
// writes the tool height z there (linear along each segment).
double ToolClosestPoint_m(const ToolContact& tool, double x_m, double y_m, double* z_m);

}  // namespace microdex::fem
