#include "common/geometry/loop_wire_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "common/mesh/mesh_fcl.h"
#include "common/mesh/primitives.h"
#include "common/mesh/triangle_mesh.h"
#include "fcl/narrowphase/distance.h"

namespace microdex::geometry {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

using mesh::TriangleMesh;

// A ring of n vertices of radius r around p in the plane ⊥ t.
void AddRing(const Eigen::Vector3d& p, const Eigen::Vector3d& t, const Eigen::Vector3d& a, double r,
             int n, TriangleMesh* mesh) {
  const Eigen::Vector3d b = t.cross(a);
  for (int j = 0; j < n; ++j) {
    const double psi = kTwoPi * j / n;
    mesh->vertices.push_back(p + r * (std::cos(psi) * a + std::sin(psi) * b));
  }
}

void ConnectRings(int first, int n, TriangleMesh* mesh) {
  for (int j = 0; j < n; ++j) {
    const int a = first + j, b = first + (j + 1) % n, c = a + n, d = b + n;
    mesh->triangles.emplace_back(a, b, d);
    mesh->triangles.emplace_back(a, d, c);
  }
}

TriangleMesh MakeWireTubeMesh(const LoopWireModel& model, const LoopWireMeshResolution& res) {
  TriangleMesh mesh;
  const double r = model.wire_radius_m();
  const int n = res.n_around;
  for (const LoopWireModel::Piece& p : model.pieces()) {
    const int first = static_cast<int>(mesh.vertices.size());
    if (p.kind == WirePieceDef::Kind::kSegment) {
      const Eigen::Vector3d a = p.t_W.unitOrthogonal();
      AddRing(p.p_W0, p.t_W, a, r, n, &mesh);
      AddRing(p.p_W1, p.t_W, a, r, n, &mesh);
      ConnectRings(first, n, &mesh);
      continue;
    }
    const int rings = std::max(1, static_cast<int>(std::ceil(res.n_major * p.sweep_rad / kTwoPi)));
    const Eigen::Vector3d axis = p.u_W.cross(p.v_W);
    for (int i = 0; i <= rings; ++i) {
      const double s = p.sweep_rad * i / rings;
      const Eigen::Vector3d radial = std::cos(s) * p.u_W + std::sin(s) * p.v_W;
      const Eigen::Vector3d t = axis.cross(radial);
      AddRing(p.p_WO + p.radius_m * radial, t, radial, r, n, &mesh);
      if (i > 0) ConnectRings(first + (i - 1) * n, n, &mesh);
    }
  }
  return mesh;
}

}  // namespace

struct LoopWireMeshModel::Impl {
  std::shared_ptr<mesh::FclMesh> loop, wire;
  double scale = 1;  // BVH lengths per metre (1/R)
  int num_triangles = 0;
};

LoopWireMeshModel::LoopWireMeshModel(const LoopWireModel& model, const LoopWireMeshResolution& res)
    : impl_(std::make_unique<Impl>()) {
  const LoopDef& loop = model.loop();
  const TriangleMesh loop_mesh = mesh::MakeTorusTubeMesh({.core_radius_m = loop.radius_m,
                                                          .tube_radius_m = loop.wire_radius_m,
                                                          .segment_angle_rad = kTwoPi,
                                                          .n_major = res.n_major,
                                                          .n_minor = res.n_minor,
                                                          .end_caps = false});
  const TriangleMesh wire_mesh = MakeWireTubeMesh(model, res);
  impl_->scale = 1 / loop.radius_m;
  impl_->loop = mesh::MakeFclMesh(loop_mesh, impl_->scale);
  impl_->wire = mesh::MakeFclMesh(wire_mesh, impl_->scale);
  impl_->num_triangles = static_cast<int>(loop_mesh.triangles.size() + wire_mesh.triangles.size());
}

LoopWireMeshModel::~LoopWireMeshModel() = default;

int LoopWireMeshModel::num_triangles() const { return impl_->num_triangles; }

LoopWireClearance LoopWireMeshModel::Calc(const Eigen::Isometry3d& X_WL) const {
  fcl::DistanceRequestd request;
  request.enable_nearest_points = true;
  fcl::DistanceResultd result;
  fcl::Transform3d tf_l = fcl::Transform3d::Identity();
  tf_l.linear() = X_WL.linear();
  tf_l.translation() = impl_->scale * X_WL.translation();
  const double distance = fcl::distance(impl_->loop.get(), tf_l, impl_->wire.get(),
                                        fcl::Transform3d::Identity(), request, result) /
                          impl_->scale;
  LoopWireClearance out;
  out.status = LoopWireStatus::kOk;
  out.p_WC = result.nearest_points[0] / impl_->scale;
  out.p_WA = result.nearest_points[1] / impl_->scale;
  out.contact = !(distance > 0);
  out.clearance_m = out.contact ? 0 : distance;
  out.distance_m = std::numeric_limits<double>::quiet_NaN();
  return out;
}

}  // namespace microdex::geometry
