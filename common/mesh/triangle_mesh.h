#pragma once
// A plain triangle mesh: vertices in metres, triangles as index triples into them, optional
// per-vertex normals. The frame of the vertices is the generator's or the file's (see
// primitives.h for each generator's frame); nothing here moves them.
//
// Orientation: the closed meshes of primitives.h have counter-clockwise triangles seen from
// outside (normals out), so the divergence-theorem volume is positive.

#include <Eigen/Core>
#include <vector>

namespace microdex::mesh {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;   // m
  std::vector<Eigen::Vector3i> triangles;  // indices into vertices, counter-clockwise from outside
  std::vector<Eigen::Vector3d> normals;    // unit, one per vertex, or empty (none)
};

// Appends `other` (its indices shifted). Normals are kept only when both meshes have them
// (or `mesh` is empty).
void AppendMesh(const TriangleMesh& other, TriangleMesh& mesh);

// Axis-aligned bounding box of the vertices (empty box, min > max, for no vertices).
struct Aabb {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(1.0);
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-1.0);
};
Aabb CalcBoundingBox(const TriangleMesh& mesh);

// Sum of the triangle areas, m².
double CalcSurfaceArea(const TriangleMesh& mesh);

// Enclosed volume by the divergence theorem, m³: Σ (a · (b × c)) / 6 over the triangles
// (a, b, c), about the bounding box centre so that a mesh far from the origin loses no digits.
// Meaningful for a closed mesh (CalcEdgeTopology(mesh).closed()); positive when the triangles are
// counter-clockwise from outside.
double CalcEnclosedVolume(const TriangleMesh& mesh);

// Edge counts of the surface. Vertices at exactly the same position are one point (a seam of
// split normals or texture coordinates is not a boundary); an edge is an unordered pair of points.
struct EdgeTopology {
  int edges = 0;                 // distinct edges
  int boundary_edges = 0;        // used by one triangle
  int non_manifold_edges = 0;    // used by three or more triangles
  int inconsistent_edges = 0;    // used by two triangles in the same direction (flipped winding)
  int degenerate_triangles = 0;  // two corners at the same point
  // Every edge shared by exactly two consistently oriented triangles, none degenerate.
  bool closed() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && inconsistent_edges == 0 &&
           degenerate_triangles == 0;
  }
};
EdgeTopology CalcEdgeTopology(const TriangleMesh& mesh);

// Area-weighted vertex normals (unit; zero for a vertex of no triangle with area), e.g. for a
// view of a mesh whose file carries none.
std::vector<Eigen::Vector3d> CalcVertexNormals(const TriangleMesh& mesh);

}  // namespace microdex::mesh
