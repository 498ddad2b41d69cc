// The mesh measures on shapes whose area, volume and edges are known by hand.
#include "common/mesh/triangle_mesh.h"

#include <gtest/gtest.h>

namespace microdex::mesh {
namespace {

// The tetrahedron (0, a e_x, b e_y, c e_z), counter-clockwise from outside: volume abc/6.
TriangleMesh MakeTetrahedron(double a, double b, double c, const Eigen::Vector3d& offset) {
  TriangleMesh mesh;
  mesh.vertices = {offset, offset + Eigen::Vector3d(a, 0, 0), offset + Eigen::Vector3d(0, b, 0),
                   offset + Eigen::Vector3d(0, 0, c)};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

TEST(TriangleMesh, TetrahedronVolumeAreaAndBox) {
  const double a = 1e-3, b = 2e-3, c = 3e-3;
  // Far from the origin: the volume is taken about the box centre and keeps its digits (about
  // the origin it would lose ~8 of them). The stored corners themselves are rounded by ~2e-15 m
  // at 10 m, 2e-12 of the edges: kFarTol.
  const Eigen::Vector3d offset(10.0, -20.0, 5.0);
  constexpr double kFarTol = 1e-11;
  const TriangleMesh mesh = MakeTetrahedron(a, b, c, offset);
  EXPECT_NEAR(CalcEnclosedVolume(mesh), a * b * c / 6, kFarTol * a * b * c);
  // Three right triangles and the slanted face, |(−a, b, 0) × (−a, 0, c)| / 2.
  const double slanted = 0.5 * std::sqrt(b * b * c * c + a * a * c * c + a * a * b * b);
  EXPECT_NEAR(CalcSurfaceArea(mesh), 0.5 * (a * b + b * c + a * c) + slanted, kFarTol * a * b);
  const Aabb box = CalcBoundingBox(mesh);
  EXPECT_EQ(box.min, offset);
  EXPECT_EQ(box.max, offset + Eigen::Vector3d(a, b, c));
  const EdgeTopology topology = CalcEdgeTopology(mesh);
  EXPECT_EQ(topology.edges, 6);
  EXPECT_TRUE(topology.closed());
}

TEST(TriangleMesh, ReversedWindingNegatesTheVolume) {
  TriangleMesh mesh = MakeTetrahedron(1e-3, 1e-3, 1e-3, Eigen::Vector3d::Zero());
  for (Eigen::Vector3i& t : mesh.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(CalcEnclosedVolume(mesh), -1e-9 / 6, 1e-21);
  EXPECT_TRUE(CalcEdgeTopology(mesh).closed());  // consistently reversed is still consistent
}

TEST(TriangleMesh, CountsBoundaryNonManifoldInconsistentAndDegenerate) {
  const TriangleMesh closed = MakeTetrahedron(1e-3, 1e-3, 1e-3, Eigen::Vector3d::Zero());
  TriangleMesh open = closed;
  open.triangles.pop_back();
  EXPECT_EQ(CalcEdgeTopology(open).boundary_edges, 3);
  EXPECT_FALSE(CalcEdgeTopology(open).closed());

  TriangleMesh fin = closed;  // a fourth triangle on the edge (0, 1)
  fin.vertices.emplace_back(0.5e-3, -1e-3, -1e-3);
  fin.triangles.emplace_back(0, 4, 1);
  const EdgeTopology fin_topology = CalcEdgeTopology(fin);
  EXPECT_EQ(fin_topology.non_manifold_edges, 1);
  EXPECT_EQ(fin_topology.boundary_edges, 2);

  TriangleMesh flipped = closed;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_EQ(CalcEdgeTopology(flipped).inconsistent_edges, 3);

  TriangleMesh degenerate = closed;
  degenerate.triangles.emplace_back(1, 1, 2);
  EXPECT_EQ(CalcEdgeTopology(degenerate).degenerate_triangles, 1);
  EXPECT_FALSE(CalcEdgeTopology(degenerate).closed());
}

TEST(TriangleMesh, SplitVerticesAtOnePositionAreOnePoint) {
  // Each triangle with its own three vertices (as a file with flat normals gives them).
  const TriangleMesh shared = MakeTetrahedron(1e-3, 2e-3, 1e-3, Eigen::Vector3d::Zero());
  TriangleMesh split;
  for (const Eigen::Vector3i& t : shared.triangles) {
    const int base = static_cast<int>(split.vertices.size());
    for (int k = 0; k < 3; ++k) split.vertices.push_back(shared.vertices[t[k]]);
    split.triangles.emplace_back(base, base + 1, base + 2);
  }
  EXPECT_TRUE(CalcEdgeTopology(split).closed());
  EXPECT_EQ(CalcEdgeTopology(split).edges, 6);
  EXPECT_DOUBLE_EQ(CalcEnclosedVolume(split), CalcEnclosedVolume(shared));
}

TEST(TriangleMesh, AppendShiftsIndicesAndNormalsOfFacesPointOut) {
  TriangleMesh mesh = MakeTetrahedron(1e-3, 1e-3, 1e-3, Eigen::Vector3d::Zero());
  AppendMesh(MakeTetrahedron(1e-3, 1e-3, 1e-3, Eigen::Vector3d(5e-3, 0, 0)), mesh);
  ASSERT_EQ(mesh.vertices.size(), 8u);
  EXPECT_EQ(mesh.triangles.back(), Eigen::Vector3i(5, 6, 7));
  EXPECT_NEAR(CalcEnclosedVolume(mesh), 2e-9 / 6, 1e-21);
  const std::vector<Eigen::Vector3d> normals = CalcVertexNormals(mesh);
  // At the corner a e_x the faces y = 0, z = 0 and the slanted one meet: all point away from
  // the opposite vertices, so the normal has a positive x.
  EXPECT_NEAR(normals[1].norm(), 1, 1e-15);
  EXPECT_GT(normals[1].x(), 0);
  // At the origin only the three coordinate faces meet, areas equal: −(1, 1, 1)/√3.
  EXPECT_LT((normals[0] + Eigen::Vector3d::Constant(1 / std::sqrt(3.0))).norm(), 1e-15);
}

}  // namespace
}  // namespace microdex::mesh
