#include "common/mesh/triangle_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <utility>

#include "common/base/check.h"

namespace microdex::mesh {
namespace {

// Point ids: vertices at exactly the same position share one id.
std::vector<int> CalcPointIds(const TriangleMesh& mesh) {
  std::map<std::array<double, 3>, int> ids;
  std::vector<int> point_of(mesh.vertices.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Eigen::Vector3d& p = mesh.vertices[v];
    const auto [it, inserted] =
        ids.try_emplace({p.x(), p.y(), p.z()}, static_cast<int>(ids.size()));
    point_of[v] = it->second;
  }
  return point_of;
}

void CheckIndices(const TriangleMesh& mesh) {
  const int n = static_cast<int>(mesh.vertices.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    MICRODEX_CHECK(t.minCoeff() >= 0 && t.maxCoeff() < n);
  }
}

}  // namespace

void AppendMesh(const TriangleMesh& other, TriangleMesh& mesh) {
  const bool keep_normals = (mesh.vertices.empty() || !mesh.normals.empty()) &&
                            other.normals.size() == other.vertices.size() &&
                            !other.vertices.empty();
  if (!keep_normals) mesh.normals.clear();
  const int base = static_cast<int>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), other.vertices.begin(), other.vertices.end());
  if (keep_normals) {
    mesh.normals.insert(mesh.normals.end(), other.normals.begin(), other.normals.end());
  }
  for (const Eigen::Vector3i& t : other.triangles) {
    mesh.triangles.push_back(t + Eigen::Vector3i::Constant(base));
  }
}

Aabb CalcBoundingBox(const TriangleMesh& mesh) {
  Aabb box;
  if (mesh.vertices.empty()) return box;
  box.min = box.max = mesh.vertices.front();
  for (const Eigen::Vector3d& v : mesh.vertices) {
    box.min = box.min.cwiseMin(v);
    box.max = box.max.cwiseMax(v);
  }
  return box;
}

double CalcSurfaceArea(const TriangleMesh& mesh) {
  CheckIndices(mesh);
  double area = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    area += 0.5 * (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
  }
  return area;
}

double CalcEnclosedVolume(const TriangleMesh& mesh) {
  CheckIndices(mesh);
  const Aabb box = CalcBoundingBox(mesh);
  const Eigen::Vector3d c = 0.5 * (box.min + box.max);
  double six_volume = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]] - c;
    const Eigen::Vector3d b = mesh.vertices[t[1]] - c;
    const Eigen::Vector3d d = mesh.vertices[t[2]] - c;
    six_volume += a.dot(b.cross(d));
  }
  return six_volume / 6;
}

EdgeTopology CalcEdgeTopology(const TriangleMesh& mesh) {
  CheckIndices(mesh);
  const std::vector<int> point_of = CalcPointIds(mesh);
  // Per unordered edge: how many triangles use it from its lower point, and from its higher.
  std::map<std::pair<int, int>, std::array<int, 2>> uses;
  EdgeTopology topology;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const int p[3] = {point_of[t[0]], point_of[t[1]], point_of[t[2]]};
    if (p[0] == p[1] || p[1] == p[2] || p[2] == p[0]) {
      ++topology.degenerate_triangles;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const int a = p[k], b = p[(k + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}][a < b ? 0 : 1];
    }
  }
  topology.edges = static_cast<int>(uses.size());
  for (const auto& [edge, count] : uses) {
    const int total = count[0] + count[1];
    if (total == 1) ++topology.boundary_edges;
    if (total >= 3) ++topology.non_manifold_edges;
    if (total == 2 && count[0] != 1) ++topology.inconsistent_edges;
  }
  return topology;
}

std::vector<Eigen::Vector3d> CalcVertexNormals(const TriangleMesh& mesh) {
  CheckIndices(mesh);
  std::vector<Eigen::Vector3d> normals(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    // |(b − a) × (c − a)| is twice the area: the sum is area-weighted.
    const Eigen::Vector3d n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (Eigen::Vector3d& n : normals) {
    const double norm = n.norm();
    n = norm > 0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero();
  }
  return normals;
}

}  // namespace microdex::mesh
