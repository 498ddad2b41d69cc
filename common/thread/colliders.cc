#include "common/thread/colliders.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>

#include "common/geometry/segment_distance.h"

namespace microdex::thread {
namespace {

// A direction perpendicular to v, for exactly coincident closest points.
Eigen::Vector3d AnyNormal(const Eigen::Vector3d& v) {
  const Eigen::Vector3d axis =
      std::abs(v.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d n = v.cross(axis);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
}

}  // namespace

Collider Collider::Sphere(const Eigen::Vector3d& c_W, double radius_m) {
  Collider c;
  c.kind = ColliderKind::kSphere;
  c.a_W = c_W;
  c.radius_m = radius_m;
  return c;
}

Collider Collider::Capsule(const Eigen::Vector3d& a_W, const Eigen::Vector3d& b_W,
                           double radius_m) {
  Collider c;
  c.kind = ColliderKind::kCapsule;
  c.a_W = a_W;
  c.b_W = b_W;
  c.radius_m = radius_m;
  return c;
}

Collider Collider::Plane(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_W) {
  Collider c;
  c.kind = ColliderKind::kPlane;
  c.a_W = p_W;
  c.b_W = n_W.normalized();
  return c;
}

bool ColliderIgnoresLink(const Collider& collider, int link) {
  if (collider.ignore_node < 0) return false;
  const int d0 = std::abs(link - collider.ignore_node);
  const int d1 = std::abs(link + 1 - collider.ignore_node);
  return d0 <= collider.ignore_links || d1 <= collider.ignore_links;
}

LinkColliderGap CalcLinkColliderGap(const Collider& collider, const Eigen::Vector3d& x0,
                                    const Eigen::Vector3d& x1, double thread_radius_m) {
  LinkColliderGap out;
  switch (collider.kind) {
    case ColliderKind::kPlane: {
      const double h0 = collider.b_W.dot(x0 - collider.a_W);
      const double h1 = collider.b_W.dot(x1 - collider.a_W);
      out.s = h0 < h1 ? 0.0 : (h1 < h0 ? 1.0 : 0.5);
      out.gap_m = std::min(h0, h1) - thread_radius_m;
      out.n_W = collider.b_W;
      return out;
    }
    case ColliderKind::kSphere: {
      out.s = geometry::ClosestSegmentPointParam(x0, x1, collider.a_W);
      const Eigen::Vector3d p = x0 + out.s * (x1 - x0);
      const Eigen::Vector3d d = p - collider.a_W;
      const double dist = d.norm();
      out.n_W = dist > 0.0 ? Eigen::Vector3d(d / dist) : AnyNormal(x1 - x0);
      out.gap_m = dist - collider.radius_m - thread_radius_m;
      return out;
    }
    case ColliderKind::kCapsule: {
      const geometry::SegmentClosest c =
          geometry::ClosestSegmentSegment(x0, x1, collider.a_W, collider.b_W);
      out.s = c.s;
      const Eigen::Vector3d d = c.p - c.q;
      out.n_W = c.distance_m > 0.0 ? Eigen::Vector3d(d / c.distance_m)
                                   : AnyNormal(collider.b_W - collider.a_W);
      out.gap_m = c.distance_m - collider.radius_m - thread_radius_m;
      return out;
    }
  }
  return out;
}

double LinkColliderGapLowerBound(const Collider& collider, const Eigen::Vector3d& x0,
                                 const Eigen::Vector3d& x1, double thread_radius_m) {
  if (collider.kind == ColliderKind::kPlane) {
    const double h0 = collider.b_W.dot(x0 - collider.a_W);
    const double h1 = collider.b_W.dot(x1 - collider.a_W);
    return std::min(h0, h1) - thread_radius_m;
  }
  // The collider's axis: a point (sphere) or a segment (capsule).
  const Eigen::Vector3d& c0 = collider.a_W;
  const Eigen::Vector3d& c1 = collider.kind == ColliderKind::kCapsule ? collider.b_W : collider.a_W;
  const Eigen::Array3d gap =
      (c0.cwiseMin(c1) - x0.cwiseMax(x1)).array().max((x0.cwiseMin(x1) - c0.cwiseMax(c1)).array());
  return gap.max(0.0).matrix().norm() - collider.radius_m - thread_radius_m;
}

}  // namespace microdex::thread
