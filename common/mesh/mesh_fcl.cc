#include "common/mesh/mesh_fcl.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/base/check.h"

namespace microdex::mesh {

std::shared_ptr<FclMesh> MakeFclMesh(const TriangleMesh& mesh, double length_scale) {
  if (!(length_scale > 0) || !std::isfinite(length_scale)) {
    throw std::invalid_argument("length_scale: expected a finite value > 0");
  }
  if (mesh.triangles.empty()) throw std::invalid_argument("mesh: no triangles");
  std::vector<fcl::Vector3d> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) points.emplace_back(length_scale * v);
  const int n = static_cast<int>(points.size());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    MICRODEX_CHECK(t.minCoeff() >= 0 && t.maxCoeff() < n);
    triangles.emplace_back(t[0], t[1], t[2]);
  }
  auto model = std::make_shared<FclMesh>();
  model->beginModel(static_cast<int>(triangles.size()), n);
  model->addSubModel(points, triangles);
  model->endModel();
  return model;
}

}  // namespace microdex::mesh
