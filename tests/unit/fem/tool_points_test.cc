#include "common/fem/tool_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace microdex::fem {
namespace {

constexpr double kPress_m = 0.01;
constexpr double kPositionTol_m = 1e-12;

TissueModel Model(int level) {
  TissueDef def;
  def.max_level = level + 2;
  def.level = level;
  return BuildTissueModel(def);
}

std::vector<ToolPoint> Place(const TissueModel& model, const ToolContact& tool,
                             MeshSelection& mesh) {
  SelectMesh(model, model.def.level, model.def.mesh, tool, mesh);
  std::vector<ToolPoint> points(512);
  const int n =
      PlaceToolPoints(model, mesh.zones, mesh.level, tool, model.def.tool_point_spacing, points);
  EXPECT_GT(n, 0);
  points.resize(std::max(n, 0));
  return points;
}

// The points ride with the tool: a shift of the tool by a fraction of a cell shifts every
// point by the same amount, same count (nothing snaps to the grid).
TEST(ToolPoints, AttachedToTheToolNotToTheGrid) {
  const TissueModel model = Model(5);
  MeshSelection mesh = MakeMeshSelection(model);
  const ToolContact bar = MakeBarTool({0.0513, 0.1031, -kPress_m}, {0.1377, 0.1031, -kPress_m});
  const std::vector<ToolPoint> a = Place(model, bar, mesh);
  const double dx = 0.37 * model.CellSizeX_m(5), dy = 0.21 * model.CellSizeY_m(5);
  ToolContact moved = bar;
  for (int k = 0; k < 2; ++k) moved.p_SP[k] += Eigen::Vector3d(dx, dy, 0);
  const std::vector<ToolPoint> b = Place(model, moved, mesh);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_NEAR(b[k].x_m - a[k].x_m, dx, kPositionTol_m) << k;
    EXPECT_NEAR(b[k].y_m - a[k].y_m, dy, kPositionTol_m) << k;
  }
  // Both ends are points; the shares add up to the tool's length.
  EXPECT_NEAR(a.front().x_m, 0.0513, kPositionTol_m);
  EXPECT_NEAR(a.back().x_m, 0.1377, kPositionTol_m);
  double length = 0;
  for (const ToolPoint& p : a) length += p.length_m;
  EXPECT_NEAR(length, 0.1377 - 0.0513, kPositionTol_m);
}

// At most `spacing` cells apart along the tool, the end-zone cells near the pressed ends.
TEST(ToolPoints, SpacingFollowsTheLocalCells) {
  const TissueModel model = Model(5);
  MeshSelection mesh = MakeMeshSelection(model);
  const ToolContact bar = MakeBarTool({0.0513, 0.1031, -kPress_m}, {0.1377, 0.1031, -kPress_m});
  const std::vector<ToolPoint> p = Place(model, bar, mesh);
  ASSERT_GT(mesh.zones.finest, 5);
  const double h = model.CellSizeX_m(5), h_end = model.CellSizeX_m(mesh.zones.finest);
  int near_end = 0;
  for (size_t k = 1; k < p.size(); ++k) {
    const double gap = p[k].x_m - p[k - 1].x_m;
    EXPECT_GT(gap, 0);
    EXPECT_LE(gap, h * (1 + 1e-9));
    const double to_end = std::min(p[k].x_m - 0.0513, 0.1377 - p[k - 1].x_m);
    if (to_end < model.def.grading * h - h) {
      EXPECT_LE(gap, h_end * (1 + 1e-9)) << "near an end at " << p[k].x_m;
      ++near_end;
    }
  }
  EXPECT_GT(near_end, 4);
}

// Each point is found in a triangle of the mesh whose barycentric coordinates rebuild it, on
// the multi-scale mesh with end zones and fans, for a tilted bar and a polyline.
TEST(ToolPoints, LocatedInTheMeshTriangleThatHoldsThem) {
  const TissueModel model = Model(5);
  MeshSelection mesh = MakeMeshSelection(model);
  const std::vector<Eigen::Vector3d> vee = {
      {0.031, 0.052, -kPress_m}, {0.1, 0.1313, -kPress_m}, {0.17, 0.061, -kPress_m}};
  for (const ToolContact& tool : {MakeBarTool({0.03, 0.04, -kPress_m}, {0.17, 0.12, -kPress_m}),
                                  MakePolylineTool(vee, 0.0)}) {
    std::vector<ToolPoint> points = Place(model, tool, mesh);
    for (ToolPoint& p : points) {
      LocateToolPoint(model, mesh, tool, p);
      double x = 0, y = 0, sum = 0;
      for (int a = 0; a < 3; ++a) {
        EXPECT_TRUE(mesh.IsActive(p.node[a]));
        EXPECT_GE(p.lambda[a], -1e-12);
        x += p.lambda[a] * model.NodeX_m(p.node[a]);
        y += p.lambda[a] * model.NodeY_m(p.node[a]);
        sum += p.lambda[a];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_NEAR(x, p.x_m, kPositionTol_m);
      EXPECT_NEAR(y, p.y_m, kPositionTol_m);
      // The triangle is one of the mesh's.
      bool found = false;
      for (int e = 0; e < mesh.num_triangles && !found; ++e)
        found = mesh.triangles[e].node == p.node;
      EXPECT_TRUE(found);
    }
  }
}

// Only pressed parts inside the domain get points: a bar rising through the surface and
// leaving the domain.
TEST(ToolPoints, OnlyPressedPartsInsideTheDomain) {
  const TissueModel model = Model(5);
  MeshSelection mesh = MakeMeshSelection(model);
  const ToolContact rising = MakeBarTool({0.05, 0.1, -kPress_m}, {0.15, 0.1, kPress_m});
  for (const ToolPoint& p : Place(model, rising, mesh)) {
    EXPECT_LT(p.u_m, 0);
    EXPECT_LT(p.x_m, 0.10 + kPositionTol_m);
  }
  const ToolContact leaving = MakeBarTool({0.15, 0.1, -kPress_m}, {0.25, 0.1, -kPress_m});
  for (const ToolPoint& p : Place(model, leaving, mesh)) EXPECT_LT(p.x_m, 0.20);
}

// The spring is 2 G t · share / Σλ|d| times the factor, and the cap on the mesh's edges.
TEST(ToolPoints, SpringConsistentWithTheKink) {
  ToolPoint p;
  p.length_m = 0.002;
  p.kink_m = 0.0005;
  const double g = 1e4, t = 0.01;
  EXPECT_DOUBLE_EQ(ToolPointSpring(p, g, t, 1.0, 1e9), 2 * g * t * 0.002 / 0.0005);
  EXPECT_DOUBLE_EQ(ToolPointSpring(p, g, t, 1.5, 1e9), 1.5 * 2 * g * t * 0.002 / 0.0005);
  p.kink_m = 0;
  EXPECT_DOUBLE_EQ(ToolPointSpring(p, g, t, 1.0, 1e5), 1e5);
}

}  // namespace
}  // namespace microdex::fem
