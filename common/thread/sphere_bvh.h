#pragma once
// Fixed-topology sphere hierarchy for thread self-collision (thesis §5.3).
//
// Leaves are the links' bounding spheres in chain order; each level above bounds pairs of
// successive spheres of the level below (an odd last one is carried up), so the tree is a
// balanced binary tree built once. Each step only the spheres move: a bottom-up refit of all
// 2 n - 1 spheres, then the FindCollision traversal.
//
// Layout: tree nodes 0..n-1 are the leaves in link order (leaf i bounds link i), inner nodes
// follow level by level, so children always precede their parent and the root is last.
//
// Precision: the spheres are single precision (x, y, z, r: one SSE register per sphere), each
// grown by a margin that covers the rounding, so a leaf still encloses its link (exact double
// positions) grown by the inflation, and a parent still encloses its children.

#include <Eigen/Core>
#include <cstdint>
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

// What the traversal reads of a node: its children as byte offsets (16 per node; 0 for a
// leaf; bit 0 set when that child has at most two links), its number of links and first link.
struct SphereBvhTraversalNode {
  std::uint32_t left_offset = 0;
  std::uint32_t right_offset = 0;
  std::int32_t size = 0;
  std::int32_t lo = 0;
};

// Two tree nodes p, q whose spheres are to be tested (all links of p precede all links of q),
// packed as byte offsets 16 p | 16 q << 32: a sphere and a traversal record are 16 bytes each.
using SphereBvhNodePair = std::uint64_t;
inline SphereBvhNodePair PackNodePair(int p, int q) {
  return (static_cast<std::uint64_t>(q) << 36) | (static_cast<std::uint64_t>(p) << 4);
}
inline int NodePairFirst(SphereBvhNodePair pq) { return static_cast<int>((pq & 0xffffffffu) >> 4); }
inline int NodePairSecond(SphereBvhNodePair pq) { return static_cast<int>(pq >> 36); }

// One level of inner nodes [begin, begin + count). The first `regular` of them have the
// children first_child + 2 k and first_child + 2 k + 1 (successive nodes of the level below);
// the others (at most one, next to a carried-up node) are refitted one by one.
struct SphereBvhLevel {
  int begin = 0;
  int count = 0;
  int regular = 0;
  int first_child = 0;
};

struct SphereBvhTopology {
  int num_leaves = 0;
  int root = -1;
  std::vector<SphereBvhNode> nodes;               // 2 n - 1, children before parents
  std::vector<int> height;                        // per node, 0 for leaves
  std::vector<SphereBvhTraversalNode> traversal;  // per node
  std::vector<SphereBvhLevel> levels;             // inner levels, bottom up
  // The traversal's starting pairs: FindCollision(left, right) of every inner node, with its
  // descent along the chain boundary unrolled (see BuildSphereBvhTopology); the pairs of two
  // leaves among them are kept apart (their test has nothing to push).
  std::vector<SphereBvhNodePair> self_pairs;
  std::vector<SphereBvhNodePair> self_leaf_pairs;
  // Largest pending-pair count of the fall-back stack traversal (checked in use).
  int max_stack = 0;

  bool IsLeaf(int node) const { return nodes[node].left < 0; }
};

// Per-step sphere data (sized at build, refitted in place) and the traversal's queue.
struct SphereBvhSpheres {
  Eigen::Matrix4Xf xyzr;  // per tree node: centre (world, m) and radius (m)
  // Chain node positions in single precision (columns x, y, z), refit scratch.
  Eigen::Matrix<float, Eigen::Dynamic, 3> nodes_W;
  // Node pairs still to test, rings of a power-of-two size: pairs with a node of more than
  // two links, and small pairs.
  std::vector<SphereBvhNodePair> queue;
  std::vector<SphereBvhNodePair> small_queue;

  Eigen::Vector3d center_W(int node) const { return xyzr.col(node).head<3>().cast<double>(); }
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

// The SIMD paths' scalar twins (tests hold them bit for bit equal; the traversal and the refit
// use the four-lane forms where the processor has them). RefitSphereBvhScalar: RefitSphereBvh
// one sphere at a time. SphereBvhSpheresOverlap: the overlap test of two (x, y, z, r) spheres
// as the traversal runs it (SSE2 where available); SphereBvhSpheresOverlapScalar: the same
// operations one lane at a time.
int RefitSphereBvhScalar(const SphereBvhTopology& topology, const Eigen::Matrix3Xd& x_W,
                         double inflate_m, SphereBvhSpheres& spheres);
bool SphereBvhSpheresOverlap(const float* a, const float* b);
bool SphereBvhSpheresOverlapScalar(const float* a, const float* b);

// Self-collision pairs by the FindCollision traversal: FindCollision(T, T) is split as
// Self(T) = Self(left) + Self(right) + FindCollision(left, right), so every pair is found
// once. The pairs are tested breadth first from a queue (the tests are independent, so they
// overlap in the processor); a full queue falls back to a fixed stack. Writes at most capacity
// pairs; returns the number found (which may exceed capacity: the excess is dropped and the
// caller records it). Never allocates.
int FindSelfCollisions(const SphereBvhTopology& topology, SphereBvhSpheres& spheres,
                       LinkPair* pairs, int capacity);

// Reference: every pair of non-adjacent leaf spheres tested directly, O(n^2), with the same
// sphere test.
int FindSelfCollisionsAllPairs(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                               LinkPair* pairs, int capacity);

}  // namespace microdex::thread
