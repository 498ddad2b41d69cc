// Sphere hierarchy (thesis §5.3) against the all-pairs reference.
#include "common/thread/sphere_bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace microdex::thread {
namespace {

Eigen::Matrix3Xd RandomWalk(int nodes, double step_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Matrix3Xd x(3, nodes);
  x.col(0).setZero();
  for (int i = 1; i < nodes; ++i) {
    Eigen::Vector3d d(g(rng), g(rng), g(rng));
    x.col(i) = x.col(i - 1) + step_m * d.normalized();
  }
  return x;
}

std::vector<std::pair<int, int>> Sorted(const std::vector<LinkPair>& pairs, int count) {
  std::vector<std::pair<int, int>> out;
  for (int k = 0; k < count; ++k) out.emplace_back(pairs[k].a, pairs[k].b);
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SphereBvh, BalancedTreeWithTwoNMinusOneSpheres) {
  for (int links : {1, 2, 3, 64, 100, 1024}) {
    const SphereBvhTopology t = BuildSphereBvhTopology(links);
    const int n = static_cast<int>(t.nodes.size());
    EXPECT_EQ(n, 2 * links - 1);
    EXPECT_EQ(t.root, 2 * links - 2);  // children before parents: the root comes last
    EXPECT_LE(t.height[t.root], static_cast<int>(std::ceil(std::log2(links))));
    for (int i = 0; i < n; ++i) {
      const SphereBvhNode& node = t.nodes[i];
      if (i < links) {  // leaves in link order
        EXPECT_TRUE(t.IsLeaf(i));
        EXPECT_EQ(node.lo, i);
        EXPECT_EQ(node.hi, i + 1);
        continue;
      }
      ASSERT_FALSE(t.IsLeaf(i));
      EXPECT_LT(node.left, i);
      EXPECT_LT(node.right, i);
      // A node covers exactly its two children's successive link ranges.
      EXPECT_EQ(node.lo, t.nodes[node.left].lo);
      EXPECT_EQ(t.nodes[node.left].hi, t.nodes[node.right].lo);
      EXPECT_EQ(node.hi, t.nodes[node.right].hi);
    }
    EXPECT_EQ(t.nodes[t.root].lo, 0);
    EXPECT_EQ(t.nodes[t.root].hi, links);
  }
}

TEST(SphereBvh, RefitEnclosesLinksAndChildren) {
  const Eigen::Matrix3Xd x = RandomWalk(65, 1e-3, 3);
  const SphereBvhTopology t = BuildSphereBvhTopology(64);
  SphereBvhSpheres s = MakeSphereBvhSpheres(t);
  EXPECT_EQ(RefitSphereBvh(t, x, 1e-5, s), 2 * 64 - 1);
  constexpr double kTol_m = 1e-12;
  for (int i = 0; i < static_cast<int>(t.nodes.size()); ++i) {
    if (t.IsLeaf(i)) {
      const int l = t.nodes[i].lo;
      for (int k : {l, l + 1}) {
        EXPECT_LE((x.col(k) - s.center_W(i)).norm() + 1e-5, s.radius_m(i) + kTol_m);
      }
    } else {
      for (int c : {t.nodes[i].left, t.nodes[i].right}) {
        EXPECT_LE((s.center_W(c) - s.center_W(i)).norm() + s.radius_m(c), s.radius_m(i) + kTol_m);
      }
    }
  }
}

TEST(SphereBvh, FindCollisionEqualsAllPairs) {
  for (unsigned seed = 0; seed < 20; ++seed) {
    const int nodes = 20 + 37 * static_cast<int>(seed);
    // A random walk in a small box folds back on itself: many overlapping spheres.
    const Eigen::Matrix3Xd x = RandomWalk(nodes, 1e-3, seed);
    const SphereBvhTopology t = BuildSphereBvhTopology(nodes - 1);
    SphereBvhSpheres s = MakeSphereBvhSpheres(t);
    RefitSphereBvh(t, x, 2e-4, s);
    std::vector<LinkPair> a(nodes * nodes), b(nodes * nodes);
    const int na = FindSelfCollisions(t, s, a.data(), static_cast<int>(a.size()));
    const int nb = FindSelfCollisionsAllPairs(t, s, b.data(), static_cast<int>(b.size()));
    ASSERT_EQ(na, nb) << "seed " << seed;
    EXPECT_GT(na, 0);
    EXPECT_EQ(Sorted(a, na), Sorted(b, nb));
    for (int k = 0; k < na; ++k) EXPECT_GE(a[k].b - a[k].a, 2);  // no same or adjacent links
  }
}

TEST(SphereBvh, OverflowIsCountedNotWritten) {
  const Eigen::Matrix3Xd x = RandomWalk(100, 1e-3, 7);
  const SphereBvhTopology t = BuildSphereBvhTopology(99);
  SphereBvhSpheres s = MakeSphereBvhSpheres(t);
  RefitSphereBvh(t, x, 1e-3, s);
  std::vector<LinkPair> pairs(4, LinkPair{-7, -7});
  const int found = FindSelfCollisions(t, s, pairs.data(), 2);
  EXPECT_GT(found, 2);
  EXPECT_EQ(pairs[2].a, -7);  // nothing written past the capacity
}

}  // namespace
}  // namespace microdex::thread
