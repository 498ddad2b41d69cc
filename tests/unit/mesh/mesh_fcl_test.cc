// Loaded meshes as FCL geometry: the distance FCL finds between two sphere meshes read back
// from files against the analytic distance between the spheres, bounded by the facets' depth.
#include "common/mesh/mesh_fcl.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/mesh/mesh_io.h"
#include "common/mesh/primitives.h"
#include "fcl/narrowphase/collision.h"
#include "fcl/narrowphase/distance.h"

namespace microdex::mesh {
namespace {

// How far inside the sphere (centre at the origin, radius R) the mesh's facets reach: R minus
// the least distance from the centre to a facet's plane. The mesh is convex and inscribed, so it
// lies between the balls of radius R − depth and R.
double CalcFacetDepth(const TriangleMesh& mesh, double R) {
  double least = R;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    const Eigen::Vector3d n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).normalized();
    least = std::min(least, std::abs(n.dot(a)));
  }
  return R - least;
}

TEST(MeshFcl, SphereMeshDistanceMatchesTheAnalyticOne) {
  const double R1 = 0.5e-3, R2 = 0.8e-3;
  const Eigen::Vector3d p_WB = 3e-3 * Eigen::Vector3d(1, -0.5, 0.8).normalized();
  const double exact = p_WB.norm() - R1 - R2;
  const Eigen::Matrix3d R_WB =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, 1, -2).normalized()).matrix();
  // The scene's length is a millimetre: the BVHs in millimetres (mesh_fcl.h).
  const double scale = 1e3;
  double previous_error = 1;
  for (int k = 1; k <= 4; k *= 2) {
    const std::string path_a = ::testing::TempDir() + "/fcl_sphere_a.ply";
    const std::string path_b = ::testing::TempDir() + "/fcl_sphere_b.glb";
    SaveMesh(MakeSphereMesh({.radius_m = R1, .n_lat = 8 * k, .n_lon = 16 * k}), path_a);
    SaveMesh(MakeSphereMesh({.radius_m = R2, .n_lat = 6 * k, .n_lon = 12 * k}), path_b);
    const TriangleMesh a = LoadMesh(path_a), b = LoadMesh(path_b);
    const auto fa = MakeFclMesh(a, scale), fb = MakeFclMesh(b, scale);
    fcl::Transform3d X_WB = fcl::Transform3d::Identity();
    X_WB.linear() = R_WB;
    X_WB.translation() = scale * p_WB;
    fcl::DistanceRequestd request;
    fcl::DistanceResultd result;
    const double d =
        fcl::distance(fa.get(), fcl::Transform3d::Identity(), fb.get(), X_WB, request, result) /
        scale;
    // Never closer than the spheres; at most both facet depths farther (float vertices: 1e-9).
    const double depths = CalcFacetDepth(a, R1) + CalcFacetDepth(b, R2);
    EXPECT_GE(d, exact - 1e-9) << k;
    EXPECT_LE(d, exact + depths + 1e-9) << k;
    const double error = d - exact;
    EXPECT_LT(error, previous_error) << k;
    previous_error = error;
  }
  EXPECT_LT(previous_error, 1e-2 * exact);
}

TEST(MeshFcl, CollidesWhereTheShapesOverlap) {
  const TriangleMesh cube = MakeBoxMesh({.size_m = Eigen::Vector3d::Constant(1e-3)});
  const auto model = MakeFclMesh(cube, 1e3);
  EXPECT_EQ(model->num_tris, 12);
  for (const double gap_m : {-0.1e-3, 0.1e-3}) {
    fcl::Transform3d X = fcl::Transform3d::Identity();
    X.translation() = 1e3 * Eigen::Vector3d(1e-3 + gap_m, 0.2e-3, 0);
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    fcl::collide(model.get(), fcl::Transform3d::Identity(), model.get(), X, request, result);
    EXPECT_EQ(result.isCollision(), gap_m < 0) << gap_m;
  }
  EXPECT_THROW(MakeFclMesh(cube, 0), std::invalid_argument);
  EXPECT_THROW(MakeFclMesh(TriangleMesh{}), std::invalid_argument);
}

}  // namespace
}  // namespace microdex::mesh
