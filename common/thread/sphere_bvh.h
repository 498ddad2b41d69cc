#pragma once
// Fixed-topology sphere hierarchy for thread self-collision (thesis §5.3).
//
// Leaves are the links' bounding spheres in chain order; each level above bounds pairs of
// successive spheres of the level below (an odd last one is carried up), so the tree is a
// balanced binary tree built once. Each step only the spheres move: a bottom-up refit of all
// 2 n - 1 spheres, then the FindCollision traversal.
//
// Layout: tree nodes 0..n-1 are the leaves in link order (leaf i bounds link i), inner nodes
// follow level by level, so children always precede their parent and the root is last. The
// spheres are packed as (x, y, z, r) per node.

#include <Eigen/Core>
#include <vector>

namespace microdex::thread {

// Two links (indices a < b) whose spheres overlap; never the same or adjacent links.
struct LinkPair {
  int a = 0;
  int b = 0;
};

struct SphereBvhNode {
  int left = -1;  // child tree nodes, -1 for a leaf
  int right = -1;
  int lo = 0;  // links [lo, hi) under this node
  int hi = 0;
};

struct SphereBvhTopology {
  int num_leaves = 0;
  int root = -1;
  std::vector<SphereBvhNode> nodes;  // 2 n - 1, children before parents
  std::vector<int> height;           // per node, 0 for leaves
  // Largest pending-pair count of the traversal's stack (fixed at build, checked in use).
  int max_stack = 0;

  bool IsLeaf(int node) const { return nodes[node].left < 0; }
};

// Per-step sphere data (sized at build, refitted in place).
struct SphereBvhSpheres {
  Eigen::Matrix4Xd xyzr;  // per tree node: centre (world, m) and radius (m)

  Eigen::Vector3d center_W(int node) const { return xyzr.col(node).head<3>(); }
  double radius_m(int node) const { return xyzr(3, node); }
};

SphereBvhTopology BuildSphereBvhTopology(int num_links);
SphereBvhSpheres MakeSphereBvhSpheres(const SphereBvhTopology& topology);

// Leaves: the minimal sphere of link i (nodes i, i + 1) grown by inflate_m (thread radius plus
// contact range). Inner spheres: the minimal sphere enclosing both children. Returns the
// number of sphere updates (2 n - 1).
int RefitSphereBvh(const SphereBvhTopology& topology, const Eigen::Matrix3Xd& x_W, double inflate_m,
                   SphereBvhSpheres& spheres);
// Only the n leaf spheres (what the all-pairs reference needs). Returns n.
int RefitSphereBvhLeaves(const SphereBvhTopology& topology, const Eigen::Matrix3Xd& x_W,
                         double inflate_m, SphereBvhSpheres& spheres);

// Self-collision pairs by the FindCollision traversal: FindCollision(T, T) is split as
// Self(T) = Self(left) + Self(right) + FindCollision(left, right), so every pair is found
// once; Self is a flat pass over the inner nodes and FindCollision runs on a fixed stack.
// Writes at most capacity pairs; returns the number found (which may exceed capacity: the
// excess is dropped and the caller records it). Never allocates.
int FindSelfCollisions(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                       LinkPair* pairs, int capacity);

// Reference: every pair of non-adjacent leaf spheres tested directly, O(n^2).
int FindSelfCollisionsAllPairs(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                               LinkPair* pairs, int capacity);

}  // namespace microdex::thread
