#pragma once
// External objects the thread touches (tools, the needle as a chain of capsules, the tissue
// surface), for the contact reaction (5.9). Poses are set by the caller before each step.

#include <Eigen/Core>

namespace microdex::thread {

enum class ColliderKind { kSphere, kCapsule, kPlane };

struct Collider {
  ColliderKind kind = ColliderKind::kSphere;
  // Sphere: centre a_W. Capsule: axis from a_W to b_W. Plane: a point a_W on it and its unit
  // normal b_W pointing to the free side.
  Eigen::Vector3d a_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d b_W = Eigen::Vector3d::Zero();
  double radius_m = 0.0;  // sphere and capsule radius; unused for planes
  bool enabled = true;
  // Links with an end node within ignore_links of ignore_node do not touch this collider:
  // a tool that grasps a node does not push the thread it holds (-1: none).
  int ignore_node = -1;
  int ignore_links = 0;

  static Collider Sphere(const Eigen::Vector3d& c_W, double radius_m);
  static Collider Capsule(const Eigen::Vector3d& a_W, const Eigen::Vector3d& b_W, double radius_m);
  static Collider Plane(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_W);
};

// Closest approach of a link (segment x0–x1 of radius thread_radius_m) to a collider.
struct LinkColliderGap {
  double s = 0.0;      // parameter of the closest point on the link, in [0, 1]
  double gap_m = 0.0;  // surface distance; negative when overlapping
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();  // unit normal from the object to the thread
};

LinkColliderGap CalcLinkColliderGap(const Collider& collider, const Eigen::Vector3d& x0,
                                    const Eigen::Vector3d& x1, double thread_radius_m);

// A lower bound of CalcLinkColliderGap's gap_m, from the distance between the link's and the
// collider's axis-aligned boxes (the exact gap for planes): a handful of comparisons, for
// skipping links far from a collider before the closest-point computation.
double LinkColliderGapLowerBound(const Collider& collider, const Eigen::Vector3d& x0,
                                 const Eigen::Vector3d& x1, double thread_radius_m);

// True when the link with end nodes (node, node + 1) is excluded from the collider.
bool ColliderIgnoresLink(const Collider& collider, int link);

}  // namespace microdex::thread
