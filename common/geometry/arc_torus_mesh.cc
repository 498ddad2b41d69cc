#include "common/geometry/arc_torus_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <stdexcept>

#include "common/mesh/mesh_fcl.h"
#include "common/mesh/mesh_io.h"
#include "common/mesh/primitives.h"
#include "fcl/narrowphase/distance.h"

namespace microdex::geometry {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

std::string FormatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

mesh::TriangleMesh LoadOrCreate(const std::string& path, const mesh::TriangleMesh& generated) {
  if (!std::filesystem::exists(path)) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    mesh::SaveMesh(generated, path);
  }
  return mesh::LoadMesh(path);
}

}  // namespace

mesh::TriangleMesh MakeNeedleRibbonMesh(double radius_m, double sweep_rad, int segments,
                                        double half_width_m) {
  mesh::TriangleMesh mesh;
  for (int i = 0; i <= segments; ++i) {
    const double s = sweep_rad * i / segments;
    const double x = radius_m * std::cos(s), y = radius_m * std::sin(s);
    mesh.vertices.emplace_back(x, y, -half_width_m);
    mesh.vertices.emplace_back(x, y, half_width_m);
  }
  for (int i = 0; i < segments; ++i) {
    const int a = 2 * i, b = 2 * i + 1, c = 2 * i + 2, d = 2 * i + 3;
    mesh.triangles.emplace_back(a, c, d);
    mesh.triangles.emplace_back(a, d, b);
  }
  return mesh;
}

struct ArcTorusMeshModel::Impl {
  std::shared_ptr<mesh::FclMesh> needle, vessel;
  Eigen::Vector3d first_vertex_N;
  double core_radius_m = 0, tube_radius_m = 0;
  double scale = 1;  // BVH lengths per metre (1/R)
  int num_triangles = 0;
};

ArcTorusMeshModel::ArcTorusMeshModel(const ArcDef& arc, const TorusSegmentDef& torus,
                                     const MeshResolution& res, const std::string& dir)
    : impl_(std::make_unique<Impl>()) {
  if (const char* error = FindArcTorusInputError(arc, torus)) throw std::invalid_argument(error);
  const int n_major =
      std::max(1, static_cast<int>(std::lround(res.n_major * torus.segment_angle_rad / kTwoPi)));
  // A ribbon a millionth of the needle radius wide: a curve for every practical purpose.
  const double half_width = 1e-6 * arc.radius_m;
  needle_path_ = dir + "/needle_ribbon_rho" + FormatNumber(arc.radius_m) + "_sweep" +
                 FormatNumber(arc.sweep_rad) + "_n" + std::to_string(res.needle_segments) + ".obj";
  vessel_path_ = dir + "/vessel_wall_R" + FormatNumber(torus.core_radius_m) + "_r" +
                 FormatNumber(torus.tube_radius_m) + "_omega" +
                 FormatNumber(torus.segment_angle_rad) + "_" + std::to_string(n_major) + "x" +
                 std::to_string(res.n_minor) + ".obj";
  const mesh::TriangleMesh needle = LoadOrCreate(
      needle_path_,
      MakeNeedleRibbonMesh(arc.radius_m, arc.sweep_rad, res.needle_segments, half_width));
  const mesh::TriangleMesh vessel = LoadOrCreate(
      vessel_path_, mesh::MakeTorusTubeMesh({.core_radius_m = torus.core_radius_m,
                                             .tube_radius_m = torus.tube_radius_m,
                                             .segment_angle_rad = torus.segment_angle_rad,
                                             .n_major = n_major,
                                             .n_minor = res.n_minor,
                                             .end_caps = false}));
  // FCL's triangle–triangle distance tests the vertex–face case only where the squared length
  // of a triangle's edge cross product exceeds 1e-15 (an absolute threshold, in length⁴):
  // millimetre-scale facets fall below it and get edge–edge distances only, up to ~1e-6 m too
  // large where a needle end faces a facet (checked against point–triangle distances). In
  // units of R the wall's facets are far above it (the needle's ribbon needs no face test).
  impl_->scale = 1 / torus.core_radius_m;
  impl_->needle = mesh::MakeFclMesh(needle, impl_->scale);
  impl_->vessel = mesh::MakeFclMesh(vessel, impl_->scale);
  impl_->first_vertex_N = needle.vertices.front();
  impl_->core_radius_m = torus.core_radius_m;
  impl_->tube_radius_m = torus.tube_radius_m;
  impl_->num_triangles = static_cast<int>(needle.triangles.size() + vessel.triangles.size());
}

ArcTorusMeshModel::~ArcTorusMeshModel() = default;

int ArcTorusMeshModel::num_triangles() const { return impl_->num_triangles; }

ArcTorusClearance ArcTorusMeshModel::Calc(const Eigen::Isometry3d& X_WN,
                                          const Eigen::Isometry3d& X_WV) const {
  fcl::DistanceRequestd request;
  request.enable_nearest_points = true;
  fcl::DistanceResultd result;
  // In the vessel frame, scaled (see the constructor): the relative pose in double, so world
  // translations cost nothing.
  const Eigen::Isometry3d X_VN = X_WV.inverse() * X_WN;
  fcl::Transform3d tf_n = fcl::Transform3d::Identity();
  tf_n.linear() = X_VN.linear();
  tf_n.translation() = impl_->scale * X_VN.translation();
  const double distance = fcl::distance(impl_->needle.get(), tf_n, impl_->vessel.get(),
                                        fcl::Transform3d::Identity(), request, result) /
                          impl_->scale;
  ArcTorusClearance out;
  out.status = ClearanceStatus::kOk;
  out.p_WD = X_WV * Eigen::Vector3d(result.nearest_points[0] / impl_->scale);
  out.p_WB = X_WV * Eigen::Vector3d(result.nearest_points[1] / impl_->scale);
  if (!(distance > 0)) {
    out.contact = true;
    out.clearance_m = 0;
    return out;
  }
  const Eigen::Vector3d p_V = X_VN * impl_->first_vertex_N;
  const double k = std::hypot(p_V.x(), p_V.y());
  const bool inside = std::hypot(k - impl_->core_radius_m, p_V.z()) < impl_->tube_radius_m;
  out.clearance_m = inside ? distance : -distance;
  out.contact = !inside;
  return out;
}

}  // namespace microdex::geometry
