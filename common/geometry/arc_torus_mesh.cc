#include "common/geometry/arc_torus_mesh.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>

#include "fcl/geometry/bvh/BVH_model.h"
#include "fcl/narrowphase/distance.h"

namespace microdex::geometry {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

std::string FormatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

// The BVH of a mesh with every length multiplied by `scale`.
std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> MakeBvh(const TriangleMesh& mesh, double scale) {
  std::vector<fcl::Vector3d> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) points.push_back(scale * v);
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto bvh = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(points.size()));
  bvh->addSubModel(points, triangles);
  bvh->endModel();
  return bvh;
}

TriangleMesh LoadOrCreate(const std::string& path, const TriangleMesh& generated) {
  if (!std::filesystem::exists(path)) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    WriteObjMesh(generated, path);
  }
  return LoadMeshWithAssimp(path);
}

}  // namespace

TriangleMesh MakeNeedleRibbonMesh(double radius_m, double sweep_rad, int segments,
                                  double half_width_m) {
  TriangleMesh mesh;
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

TriangleMesh MakeTorusWallMesh(double core_radius_m, double tube_radius_m, double segment_angle_rad,
                               int n_major, int n_minor) {
  const bool closed = segment_angle_rad >= kTwoPi;
  const int rings = closed ? n_major : n_major + 1;
  TriangleMesh mesh;
  for (int i = 0; i < rings; ++i) {
    const double phi = segment_angle_rad * i / n_major;
    for (int j = 0; j < n_minor; ++j) {
      const double psi = kTwoPi * j / n_minor;
      const double w = core_radius_m + tube_radius_m * std::cos(psi);
      mesh.vertices.emplace_back(w * std::cos(phi), w * std::sin(phi),
                                 tube_radius_m * std::sin(psi));
    }
  }
  for (int i = 0; i < n_major; ++i) {
    const int i1 = (i + 1) % rings;
    for (int j = 0; j < n_minor; ++j) {
      const int j1 = (j + 1) % n_minor;
      const int a = i * n_minor + j, b = i1 * n_minor + j, c = i1 * n_minor + j1,
                d = i * n_minor + j1;
      mesh.triangles.emplace_back(a, b, c);
      mesh.triangles.emplace_back(a, c, d);
    }
  }
  return mesh;
}

void WriteObjMesh(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << "# microdex generated mesh, metres\n";
  char line[128];
  for (const Eigen::Vector3d& v : mesh.vertices) {
    std::snprintf(line, sizeof(line), "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
    out << line;
  }
  for (const Eigen::Vector3i& t : mesh.triangles) {
    out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  if (!out) throw std::runtime_error(path + ": write failed");
}

TriangleMesh LoadMeshWithAssimp(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate);
  if (scene == nullptr) {
    throw std::runtime_error(path + ": assimp could not read it: " + importer.GetErrorString());
  }
  TriangleMesh mesh;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    const int base = static_cast<int>(mesh.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      mesh.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no area
      mesh.triangles.emplace_back(base + static_cast<int>(face.mIndices[0]),
                                  base + static_cast<int>(face.mIndices[1]),
                                  base + static_cast<int>(face.mIndices[2]));
    }
  }
  if (mesh.triangles.empty()) throw std::runtime_error(path + ": no triangles");
  return mesh;
}

struct ArcTorusMeshModel::Impl {
  std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> needle, vessel;
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
  const TriangleMesh needle = LoadOrCreate(
      needle_path_,
      MakeNeedleRibbonMesh(arc.radius_m, arc.sweep_rad, res.needle_segments, half_width));
  const TriangleMesh vessel =
      LoadOrCreate(vessel_path_, MakeTorusWallMesh(torus.core_radius_m, torus.tube_radius_m,
                                                   torus.segment_angle_rad, n_major, res.n_minor));
  // FCL's triangle–triangle distance tests the vertex–face case only where the squared length
  // of a triangle's edge cross product exceeds 1e-15 (an absolute threshold, in length⁴):
  // millimetre-scale facets fall below it and get edge–edge distances only, up to ~1e-6 m too
  // large where a needle end faces a facet (checked against point–triangle distances). In
  // units of R the wall's facets are far above it (the needle's ribbon needs no face test).
  impl_->scale = 1 / torus.core_radius_m;
  impl_->needle = MakeBvh(needle, impl_->scale);
  impl_->vessel = MakeBvh(vessel, impl_->scale);
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
