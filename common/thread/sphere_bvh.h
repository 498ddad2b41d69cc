#pragma once
// Fixed-topology sphere hierarchy for thread self-collision (thesis §5.3).
//
// Leaves are the links' bounding spheres in chain order; each inner sphere bounds two
// successive children, so the tree is a balanced binary tree built once. Each step only the
// spheres move: a bottom-up refit of all 2n - 1 spheres, then the FindCollision recursion.

#include <Eigen/Core>
#include <vector>

namespace microdex::thread {

// Two links (indices a < b) whose spheres overlap; never the same or adjacent links.
struct LinkPair {
  int a = 0;
  int b = 0;
};

struct SphereBvhTopology {
  int num_leaves = 0;
  int root = -1;
  // Per tree node, stored in post-order (children before their parent), 2 n - 1 entries.
  std::vector<int> left;       // child index, -1 for a leaf
  std::vector<int> right;      // child index, -1 for a leaf
  std::vector<int> leaf_link;  // link index of a leaf, -1 for an inner node
  std::vector<int> height;     // 0 for leaves
  std::vector<int> leaf_node;  // per link: its leaf's tree node
};

// Per-step sphere data (sized at build, refitted in place).
struct SphereBvhSpheres {
  Eigen::Matrix3Xd center_W;  // 3 x (2 n - 1)
  Eigen::VectorXd radius_m;   // 2 n - 1
};

SphereBvhTopology BuildSphereBvhTopology(int num_links);
SphereBvhSpheres MakeSphereBvhSpheres(const SphereBvhTopology& topology);

// Leaves: the minimal sphere of link i (nodes i, i + 1) grown by inflate_m (thread radius plus
// contact range). Inner spheres: the minimal sphere enclosing both children. Returns the
// number of sphere updates (2 n - 1).
int RefitSphereBvh(const SphereBvhTopology& topology, const Eigen::Matrix3Xd& x_W, double inflate_m,
                   SphereBvhSpheres& spheres);

// Self-collision pairs by the FindCollision recursion, FindCollision(T, T) split as
// Self(T) = Self(left) + Self(right) + FindCollision(left, right) so that every pair is found
// once. Writes at most capacity pairs; returns the number found (which may exceed capacity:
// the excess is dropped and the caller records it).
int FindSelfCollisions(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                       LinkPair* pairs, int capacity);

// Reference: every pair of non-adjacent leaf spheres tested directly, O(n^2).
int FindSelfCollisionsAllPairs(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                               LinkPair* pairs, int capacity);

}  // namespace microdex::thread
