#include "common/fem/multiscale_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <utility>

namespace microdex::fem {
namespace {

constexpr double kAreaTol_m2 = 1e-13;  // rounding of a sum of up to 8k triangle areas

TissueModel Model(int level, double grading = 2.0) {
  TissueDef def;
  def.max_level = level;
  def.level = level;
  def.grading = grading;
  return BuildTissueModel(def);
}

// Conforming: every edge inside the domain is shared by exactly two triangles with opposite
// orientation, every boundary edge belongs to one; a hanging node would leave a long edge
// with one triangle and two short edges with one each. The triangles tile the domain.
void ExpectConforming(const TissueModel& model, const MeshSelection& mesh) {
  std::map<std::pair<int, int>, int> directed;
  double area = 0;
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const Triangle& t = mesh.triangles[e];
    const double x0 = model.NodeX_m(t.node[0]), y0 = model.NodeY_m(t.node[0]);
    const double x1 = model.NodeX_m(t.node[1]), y1 = model.NodeY_m(t.node[1]);
    const double x2 = model.NodeX_m(t.node[2]), y2 = model.NodeY_m(t.node[2]);
    const double a = 0.5 * ((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0));
    ASSERT_GT(a, 0) << "triangle " << e << " not counter-clockwise";
    area += a;
    for (int k = 0; k < 3; ++k) ++directed[{t.node[k], t.node[(k + 1) % 3]}];
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(mesh.IsActive(t.node[k]));
  }
  EXPECT_NEAR(area, model.def.length_x_m * model.def.length_y_m, kAreaTol_m2);
  for (const auto& [edge, count] : directed) {
    ASSERT_EQ(count, 1);
    const int n = model.cells_per_side, side = model.nodes_per_side;
    const int ia = edge.first % side, ja = edge.first / side;
    const int ib = edge.second % side, jb = edge.second / side;
    const bool boundary = (ia == 0 && ib == 0) || (ja == 0 && jb == 0) || (ia == n && ib == n) ||
                          (ja == n && jb == n);
    const bool twin = directed.count({edge.second, edge.first}) == 1;
    EXPECT_TRUE(twin || boundary) << "edge " << edge.first << "–" << edge.second
                                  << " has a neighbour on one side only (hanging node)";
  }
}

TEST(MultiscaleMesh, FineMeshIsTheUniformGrid) {
  const TissueModel model = Model(5);
  MeshSelection mesh = MakeMeshSelection(model);
  SelectMesh(model, 5, MeshKind::kFine, MakeBarTool({0.05, 0.1, -0.01}, {0.15, 0.1, -0.01}), mesh);
  EXPECT_EQ(mesh.num_leaves, 32 * 32);
  EXPECT_EQ(mesh.num_triangles, 2 * 32 * 32);
  EXPECT_EQ(mesh.num_active_nodes, 33 * 33);
  ExpectConforming(model, mesh);
}

TEST(MultiscaleMesh, ConformingForManyToolsAndGradings) {
  const Eigen::Vector3d polyline[] = {
      {0.02, 0.03, -0.01}, {0.11, 0.07, -0.01}, {0.13, 0.18, -0.01}};
  const ToolContact tools[] = {
      MakeBarTool({0.05, 0.1, -0.01}, {0.15, 0.1, -0.01}),
      MakeBarTool({0.0, 0.02, -0.01}, {0.07, 0.0, -0.01}),  // touching the boundary
      MakeBarTool({0.031, 0.077, -0.01}, {0.173, 0.141, -0.01}),
      MakePointTool({0.1234, 0.0567, -0.01}, 0.0),
      MakePointTool({0.1, 0.1, -0.01}, 0.02),
      MakePolylineTool(polyline, 0.0),
      MakeBarTool({0.3, 0.3, -0.01}, {0.4, 0.35, -0.01}),  // outside the domain
  };
  for (double grading : {1.5, 2.0, 4.0}) {
    for (int level : {3, 6}) {
      const TissueModel model = Model(level, grading);
      MeshSelection mesh = MakeMeshSelection(model);
      for (const ToolContact& tool : tools) {
        SelectMesh(model, level, MeshKind::kMultiscale, tool, mesh);
        ExpectConforming(model, mesh);
      }
    }
  }
}

TEST(MultiscaleMesh, FinestCellsUnderTheToolAndFewerUnknowns) {
  const TissueModel model = Model(6);
  MeshSelection mesh = MakeMeshSelection(model);
  const ToolContact bar = MakeBarTool({0.05, 0.1, -0.01}, {0.15, 0.1, -0.01});
  SelectMesh(model, 6, MeshKind::kMultiscale, bar, mesh);
  int finest_touching = 0;
  for (int k = 0; k < mesh.num_leaves; ++k) {
    const Leaf& leaf = mesh.leaves[k];
    const double hx = model.CellSizeX_m(leaf.level), hy = model.CellSizeY_m(leaf.level);
    const double d =
        ToolBoxDistance_m(bar, leaf.ci * hx, leaf.cj * hy, (leaf.ci + 1) * hx, (leaf.cj + 1) * hy);
    if (d == 0) {
      EXPECT_EQ(leaf.level, 6);
      ++finest_touching;
    }
  }
  EXPECT_GT(finest_touching, 0);
  EXPECT_LT(mesh.num_active_nodes, 65 * 65 / 3);
  // The same tool gives the same leaves: the signature is a function of the selection.
  const std::uint64_t signature = mesh.signature;
  SelectMesh(model, 6, MeshKind::kMultiscale, bar, mesh);
  EXPECT_EQ(mesh.signature, signature);
  SelectMesh(model, 6, MeshKind::kMultiscale, MakeBarTool({0.06, 0.1, -0.01}, {0.16, 0.1, -0.01}),
             mesh);
  EXPECT_NE(mesh.signature, signature);
}

}  // namespace
}  // namespace microdex::fem
