#include "common/fem/multiscale_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <utility>

namespace microdex::fem {
namespace {

constexpr double kAreaTol_m2 = 1e-13;  // rounding of a sum of up to 8k triangle areas

// Room for the default end grading (two levels beyond `level` around bar ends).
TissueModel Model(int level, double grading = 2.0) {
  TissueDef def;
  def.max_level = level + 2;
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

// Leaves touching the bar are at the nominal level, except near its two ends where the end
// grading goes on to the end level (cells ≤ bar length / 64: level 7 for the 10 cm bar): the
// leaves at the end points are at that level,
// and no leaf finer than the nominal level is far from an end.
TEST(MultiscaleMesh, FinestCellsUnderTheToolAndFewerUnknowns) {
  const TissueModel model = Model(6);
  const int level = 6, finest = 7;
  MeshSelection mesh = MakeMeshSelection(model);
  const ToolContact bar = MakeBarTool({0.05, 0.1, -0.01}, {0.15, 0.1, -0.01});
  SelectMesh(model, level, MeshKind::kMultiscale, bar, mesh);
  EXPECT_EQ(mesh.zones.finest, finest);
  int finest_touching = 0, at_ends = 0;
  const double h = model.CellSizeX_m(level) * 1.5;  // zone radius + a finer cell diagonal
  for (int k = 0; k < mesh.num_leaves; ++k) {
    const Leaf& leaf = mesh.leaves[k];
    const double hx = model.CellSizeX_m(leaf.level), hy = model.CellSizeY_m(leaf.level);
    const double x0 = leaf.ci * hx, y0 = leaf.cj * hy;
    const double d = ToolBoxDistance_m(bar, x0, y0, x0 + hx, y0 + hy);
    const double d_end =
        std::min(ToolBoxDistance_m(MakePointTool(bar.p_SP[0], 0), x0, y0, x0 + hx, y0 + hy),
                 ToolBoxDistance_m(MakePointTool(bar.p_SP[1], 0), x0, y0, x0 + hx, y0 + hy));
    if (d == 0) {
      EXPECT_GE(leaf.level, level);
      ++finest_touching;
    }
    EXPECT_LE(leaf.level, finest);
    if (leaf.level > level) {  // its parent was refined by the end rule
      const double hp = 2 * hx, xp = (leaf.ci / 2) * hp, yp = (leaf.cj / 2) * hp;
      const double d_parent =
          std::min(ToolBoxDistance_m(MakePointTool(bar.p_SP[0], 0), xp, yp, xp + hp, yp + hp),
                   ToolBoxDistance_m(MakePointTool(bar.p_SP[1], 0), xp, yp, xp + hp, yp + hp));
      EXPECT_LT(d_parent, model.def.grading * hp);
      EXPECT_LT(d_end, model.def.grading * h);  // and it is well inside the level-6 zone
    }
    if (d_end == 0) {
      EXPECT_EQ(leaf.level, finest);
      ++at_ends;
    }
  }
  EXPECT_GE(at_ends, 4);  // the end points are grid nodes: ≥ 2 leaves meet at each
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

int FinestLeafLevel(const MeshSelection& mesh) {
  int finest = 0;
  for (int k = 0; k < mesh.num_leaves; ++k) finest = std::max<int>(finest, mesh.leaves[k].level);
  return finest;
}

// End grading applies to the pressed vertices of a bar or polyline of zero contact radius; a
// point tool, a rounded tool (contact radius > 0), an unpressed bar and end_resolution 0 keep
// the nominal level.
TEST(MultiscaleMesh, EndGradingOnlyWhereTheContactEndsSharply) {
  const TissueModel model = Model(5);
  MeshSelection mesh = MakeMeshSelection(model);
  const Eigen::Vector3d a{0.05, 0.1, -0.01}, b{0.15, 0.1, -0.01};
  SelectMesh(model, 5, MeshKind::kMultiscale, MakeBarTool(a, b), mesh);
  EXPECT_EQ(FinestLeafLevel(mesh), 7);
  EXPECT_EQ(mesh.zones.num_vertices, 2);
  const int graded_nodes = mesh.num_active_nodes;
  SelectMesh(model, 5, MeshKind::kMultiscale, MakePointTool(a, 0.0), mesh);
  EXPECT_EQ(FinestLeafLevel(mesh), 5);
  ToolContact rounded = MakeBarTool(a, b);
  rounded.contact_radius_m = 1e-3;
  SelectMesh(model, 5, MeshKind::kMultiscale, rounded, mesh);
  EXPECT_EQ(FinestLeafLevel(mesh), 5);
  SelectMesh(model, 5, MeshKind::kMultiscale, MakeBarTool({0.05, 0.1, 0.01}, {0.15, 0.1, -0.01}),
             mesh);  // one end in the air
  EXPECT_EQ(mesh.zones.num_vertices, 1);
  SelectMesh(model, 5, MeshKind::kFine, MakeBarTool(a, b), mesh);
  EXPECT_EQ(FinestLeafLevel(mesh), 5);

  TissueDef def = model.def;
  def.end_resolution = 0;
  const TissueModel plain = BuildTissueModel(def);
  MeshSelection plain_mesh = MakeMeshSelection(plain);
  SelectMesh(plain, 5, MeshKind::kMultiscale, MakeBarTool(a, b), plain_mesh);
  EXPECT_EQ(FinestLeafLevel(plain_mesh), 5);
  // A few hundred nodes more for the two ends (README: "unknowns").
  EXPECT_GT(graded_nodes, plain_mesh.num_active_nodes);
  EXPECT_LT(graded_nodes, plain_mesh.num_active_nodes + 400);
}

// The worst case the capacities are sized for: 16 pressed vertices, each with its own end
// zone, on a 2:1 domain at a wide grading. The mesh stays conforming and within the bounds.
TEST(MultiscaleMesh, SixteenVertexPolylineFitsTheCapacities) {
  TissueDef def;
  def.length_x_m = 0.2;
  def.length_y_m = 0.1;
  def.level = 4;
  def.max_level = 8;
  def.end_resolution = 1e4;  // capped at max_level
  def.end_levels = 4;
  def.grading = 4.0;
  const TissueModel model = BuildTissueModel(def);
  MeshSelection mesh = MakeMeshSelection(model);
  std::array<Eigen::Vector3d, kMaxToolPoints> zigzag;
  for (int k = 0; k < kMaxToolPoints; ++k)
    zigzag[k] = {0.01 + 0.012 * k, k % 2 ? 0.08 : 0.02, -0.01};
  SelectMesh(model, 4, MeshKind::kMultiscale, MakePolylineTool(zigzag, 0.0), mesh);
  EXPECT_EQ(mesh.zones.num_vertices, kMaxToolPoints);
  EXPECT_EQ(FinestLeafLevel(mesh), 8);
  EXPECT_LE(mesh.num_leaves, model.max_leaves);
  EXPECT_LE(mesh.num_triangles, model.max_triangles);
  EXPECT_LE(mesh.num_active_nodes, model.max_mesh_nodes);
  ExpectConforming(model, mesh);
}

}  // namespace
}  // namespace microdex::fem
