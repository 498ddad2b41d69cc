// Sphere hierarchy (thesis §5.3) against the all-pairs reference and exact segment distances.
#include "common/thread/sphere_bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "common/geometry/segment_distance.h"
#include "tests/support/knot_shapes.h"

namespace microdex::thread {
namespace {

using geometry::ClosestSegmentSegment;

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

// A polyline resampled to `nodes` points of equal spacing along it, scaled so that the links
// are link_m long.
Eigen::Matrix3Xd Resample(const std::vector<Eigen::Vector3d>& curve, int nodes, double link_m) {
  std::vector<double> s(curve.size(), 0.0);
  for (size_t k = 1; k < curve.size(); ++k) s[k] = s[k - 1] + (curve[k] - curve[k - 1]).norm();
  Eigen::Matrix3Xd x(3, nodes);
  size_t k = 0;
  for (int i = 0; i < nodes; ++i) {
    const double si = s.back() * i / (nodes - 1);
    while (k + 2 < curve.size() && s[k + 1] < si) ++k;
    const double w = (si - s[k]) / std::max(s[k + 1] - s[k], 1e-300);
    x.col(i) = (1.0 - w) * curve[k] + w * curve[k + 1];
  }
  const double scale = link_m / (s.back() / (nodes - 1));
  return x * scale;
}

// The speed benchmark's worst case: 257 nodes of 50 um coiled at a 0.6 mm radius, 4 thread
// diameters (100 um) per turn.
Eigen::Matrix3Xd TightHelix() {
  const int n = 257;
  const double link_m = 50e-6, radius_m = 0.6e-3, pitch_m = 100e-6;
  const double dphi = link_m / radius_m;
  Eigen::Matrix3Xd x(3, n);
  for (int i = 0; i < n; ++i) {
    x.col(i) = Eigen::Vector3d(radius_m * std::cos(i * dphi), radius_m * std::sin(i * dphi),
                               pitch_m * i * dphi / (2.0 * M_PI));
  }
  return x;
}

std::vector<std::pair<int, int>> Sorted(const std::vector<LinkPair>& pairs, int count) {
  std::vector<std::pair<int, int>> out;
  for (int k = 0; k < count; ++k) out.emplace_back(pairs[k].a, pairs[k].b);
  std::sort(out.begin(), out.end());
  return out;
}

// FindCollision and all pairs on the same spheres: the same set, each pair once, no
// neighbours. Returns the number of pairs.
int ExpectSameAsAllPairs(const Eigen::Matrix3Xd& x, double inflate_m, const char* what) {
  const int links = static_cast<int>(x.cols()) - 1;
  const SphereBvhTopology t = BuildSphereBvhTopology(links);
  SphereBvhSpheres s = MakeSphereBvhSpheres(t);
  EXPECT_EQ(RefitSphereBvh(t, x, inflate_m, s), 2 * links - 1);
  const int capacity = links * links + 1;
  std::vector<LinkPair> a(capacity), b(capacity);
  const int na = FindSelfCollisions(t, s, a.data(), capacity);
  const int nb = FindSelfCollisionsAllPairs(t, s, b.data(), capacity);
  EXPECT_EQ(na, nb) << what;
  const auto sa = Sorted(a, na);
  EXPECT_EQ(sa, Sorted(b, nb)) << what;
  EXPECT_EQ(std::adjacent_find(sa.begin(), sa.end()), sa.end()) << what << ": a pair twice";
  for (const auto& [la, lb] : sa) EXPECT_GE(lb - la, 2) << what;
  return na;
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
      EXPECT_EQ(t.traversal[i].size, node.hi - node.lo);
      if (i < links) {  // leaves in link order
        EXPECT_TRUE(t.IsLeaf(i));
        EXPECT_EQ(node.lo, i);
        EXPECT_EQ(node.hi, i + 1);
        continue;
      }
      ASSERT_FALSE(t.IsLeaf(i));
      EXPECT_LT(node.left, i);
      EXPECT_LT(node.right, i);
      EXPECT_EQ(t.traversal[i].lo, node.lo);
      // Children as byte offsets, bit 0 flagging a child of at most two links.
      for (auto [offset, child] : {std::pair{t.traversal[i].left_offset, node.left},
                                   std::pair{t.traversal[i].right_offset, node.right}}) {
        EXPECT_EQ(offset & ~15u, 16u * child);
        EXPECT_EQ(offset & 15u, t.nodes[child].hi - t.nodes[child].lo <= 2 ? 1u : 0u);
      }
      // A node covers exactly its two children's successive link ranges.
      EXPECT_EQ(node.lo, t.nodes[node.left].lo);
      EXPECT_EQ(t.nodes[node.left].hi, t.nodes[node.right].lo);
      EXPECT_EQ(node.hi, t.nodes[node.right].hi);
    }
    EXPECT_EQ(t.nodes[t.root].lo, 0);
    EXPECT_EQ(t.nodes[t.root].hi, links);
    // The refit schedule visits every inner node once, after its children.
    std::vector<int> seen(n, 0);
    for (const SphereBvhLevel& lv : t.levels) {
      for (int k = 0; k < lv.count; ++k) {
        const int i = lv.begin + k;
        ++seen[i];
        if (k < lv.regular) {
          EXPECT_EQ(t.nodes[i].left, lv.first_child + 2 * k);
          EXPECT_EQ(t.nodes[i].right, lv.first_child + 2 * k + 1);
        }
        EXPECT_LT(t.nodes[i].left, lv.begin);
        EXPECT_LT(t.nodes[i].right, lv.begin);
      }
    }
    for (int i = links; i < n; ++i) EXPECT_EQ(seen[i], 1);
  }
}

// The starting pairs (the unrolled boundary descents) cover every pair of links that are
// neither the same nor neighbours exactly once, and none else.
TEST(SphereBvh, StartingPairsCoverEveryCandidateOnce) {
  for (int links = 1; links <= 140; ++links) {
    const SphereBvhTopology t = BuildSphereBvhTopology(links);
    std::vector<int> covered(links * links, 0);
    auto cover = [&](SphereBvhNodePair pq) {
      const SphereBvhNode& p = t.nodes[NodePairFirst(pq)];
      const SphereBvhNode& q = t.nodes[NodePairSecond(pq)];
      for (int a = p.lo; a < p.hi; ++a) {
        for (int b = q.lo; b < q.hi; ++b) ++covered[a * links + b];
      }
    };
    for (SphereBvhNodePair pq : t.self_pairs) {
      // More than two leaf pairs below (one or two are kept as leaf pairs).
      EXPECT_GT(t.traversal[NodePairFirst(pq)].size * t.traversal[NodePairSecond(pq)].size, 2);
      cover(pq);
    }
    for (SphereBvhNodePair pq : t.self_leaf_pairs) {
      EXPECT_LT(NodePairSecond(pq), links);  // two leaves
      cover(pq);
    }
    for (int a = 0; a < links; ++a) {
      for (int b = 0; b < links; ++b) {
        ASSERT_EQ(covered[a * links + b], b - a >= 2 ? 1 : 0)
            << links << " links, " << a << "-" << b;
      }
    }
  }
}

// Single-precision spheres with their margins still enclose the exact (double) links grown
// by the inflation, and the children, at micrometre scale near and far from the origin.
TEST(SphereBvh, RefitEnclosesLinksAndChildren) {
  constexpr double kInflate_m = 37.5e-6;
  for (double offset_m : {0.0, 0.5, -3.0}) {
    Eigen::Matrix3Xd x = RandomWalk(258, 50e-6, 3);
    x.colwise() += Eigen::Vector3d(offset_m, -0.7 * offset_m, 0.3 * offset_m);
    const SphereBvhTopology t = BuildSphereBvhTopology(257);
    SphereBvhSpheres s = MakeSphereBvhSpheres(t);
    EXPECT_EQ(RefitSphereBvh(t, x, kInflate_m, s), 2 * 257 - 1);
    for (int i = 0; i < static_cast<int>(t.nodes.size()); ++i) {
      if (t.IsLeaf(i)) {
        const int l = t.nodes[i].lo;
        for (int k : {l, l + 1}) {
          EXPECT_LE((x.col(k) - s.center_W(i)).norm() + kInflate_m, s.radius_m(i))
              << "offset " << offset_m << " leaf " << i;
        }
        // Not larger than needed by more than twice the documented rounding margin
        // (2^-18 relative, 2^-21 of the end points' L1 norms).
        const double exact = 0.5 * (x.col(l + 1) - x.col(l)).norm() + kInflate_m;
        const double l1 = x.col(l).lpNorm<1>() + x.col(l + 1).lpNorm<1>();
        EXPECT_LE(s.radius_m(i), exact * (1.0 + 0x1p-17) + 0x1p-20 * l1);
      } else {
        for (int c : {t.nodes[i].left, t.nodes[i].right}) {
          EXPECT_LE((s.center_W(c) - s.center_W(i)).norm() + s.radius_m(c), s.radius_m(i))
              << "offset " << offset_m << " node " << i;
        }
      }
    }
  }
}

// The four-lane refit and its scalar twin: the same IEEE operations in the same order, so the
// same bits, for every tree shape (sizes around multiples of four, odd nodes carried up) and
// for coordinates far from the origin and very small.
TEST(SphereBvh, SimdRefitEqualsItsScalarTwin) {
  int compared = 0;
  for (int nodes = 2; nodes <= 70; ++nodes) {
    for (const double offset_m : {0.0, 3.0, -1e3}) {
      for (const double step_m : {50e-6, 1e-9}) {
        Eigen::Matrix3Xd x = RandomWalk(nodes, step_m, 7 * nodes + 1);
        x.colwise() += Eigen::Vector3d(offset_m, -0.5 * offset_m, 0.25 * offset_m);
        const SphereBvhTopology t = BuildSphereBvhTopology(nodes - 1);
        SphereBvhSpheres simd = MakeSphereBvhSpheres(t), scalar = MakeSphereBvhSpheres(t);
        RefitSphereBvh(t, x, 37.5e-6, simd);
        RefitSphereBvhScalar(t, x, 37.5e-6, scalar);
        ASSERT_EQ(simd.xyzr.size(), scalar.xyzr.size());
        ASSERT_EQ(std::memcmp(simd.xyzr.data(), scalar.xyzr.data(),
                              sizeof(float) * static_cast<size_t>(simd.xyzr.size())),
                  0)
            << nodes << " nodes, offset " << offset_m << ", step " << step_m;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 69 * 6);
}

TEST(SphereBvh, SimdOverlapEqualsItsScalarTwin) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  alignas(16) float a[4], b[4];
  int overlaps = 0, tangent = 0;
  for (int k = 0; k < 200000; ++k) {
    for (int i = 0; i < 3; ++i) {
      a[i] = u(rng);
      b[i] = u(rng);
    }
    a[3] = 0.5f * std::abs(u(rng));
    const float d = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                              (a[2] - b[2]) * (a[2] - b[2]));
    // A third of the pairs just touching (within rounding), where the two could disagree.
    b[3] = k % 3 == 0 ? d - a[3] : 0.5f * std::abs(u(rng));
    tangent += k % 3 == 0;
    const bool simd = SphereBvhSpheresOverlap(a, b);
    ASSERT_EQ(simd, SphereBvhSpheresOverlapScalar(a, b)) << "pair " << k;
    overlaps += simd;
  }
  EXPECT_GT(overlaps, 50000);
  EXPECT_GT(tangent, 60000);
}

TEST(SphereBvh, FindCollisionEqualsAllPairsOnRandomWalks) {
  for (unsigned seed = 0; seed < 20; ++seed) {
    const int nodes = 20 + 37 * static_cast<int>(seed);
    // A random walk in a small box folds back on itself: many overlapping spheres.
    EXPECT_GT(ExpectSameAsAllPairs(RandomWalk(nodes, 1e-3, seed), 2e-4, "random walk"), 0);
  }
  // Every small size, including the ones whose levels carry an odd node up.
  for (int nodes = 2; nodes <= 80; ++nodes) {
    ExpectSameAsAllPairs(RandomWalk(nodes, 50e-6, 100 + nodes), 37.5e-6, "small");
  }
}

TEST(SphereBvh, FindCollisionEqualsAllPairsOnKnots) {
  namespace ks = knot::shapes;
  // Thread-like scale: links of two diameters, spheres grown by radius + cutoff + margin.
  constexpr double kLink_m = 50e-6;
  constexpr double kInflate_m = 37.5e-6;
  EXPECT_GT(
      ExpectSameAsAllPairs(Resample(ks::TorusKnot(2, 3, 400), 257, kLink_m), kInflate_m, "trefoil"),
      0);
  EXPECT_GT(ExpectSameAsAllPairs(Resample(ks::OverhandAsTied(2, true), 385, kLink_m), kInflate_m,
                                 "double overhand"),
            0);
  EXPECT_GT(ExpectSameAsAllPairs(Resample(ks::FigureEightCurve(500), 300, kLink_m), kInflate_m,
                                 "figure eight"),
            0);
  // The tight helix: each turn lies on the next, hundreds of pairs.
  EXPECT_GT(ExpectSameAsAllPairs(TightHelix(), kInflate_m, "helix"), 700);
}

// Everything overlaps: the queue overflows and the traversal finishes on the stack.
TEST(SphereBvh, FullQueueFallsBackToTheStack) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1e-4);
  Eigen::Matrix3Xd x(3, 301);
  for (int i = 0; i < x.cols(); ++i) x.col(i) = Eigen::Vector3d(u(rng), u(rng), u(rng));
  const SphereBvhTopology t = BuildSphereBvhTopology(300);
  const SphereBvhSpheres s = MakeSphereBvhSpheres(t);
  ASSERT_LT(s.queue.size(), 300u * 299u / 2u);
  EXPECT_EQ(ExpectSameAsAllPairs(x, 1e-3, "ball"), 300 * 299 / 2 - 299);  // all but neighbours
}

// A crumpled thread (each link near ~100 others): more pairs of two-link nodes than the
// small-pair ring holds, so it is drained on the way.
TEST(SphereBvh, FullSmallPairQueueIsDrained) {
  const Eigen::Matrix3Xd x = RandomWalk(401, 1e-3, 11);
  const SphereBvhTopology t = BuildSphereBvhTopology(400);
  ASSERT_LE(MakeSphereBvhSpheres(t).small_queue.size(), 4096u);
  EXPECT_GT(ExpectSameAsAllPairs(x, 3e-3, "crumpled"), 10000);
}

TEST(SphereBvh, OverflowIsCountedNotWritten) {
  const Eigen::Matrix3Xd x = RandomWalk(100, 1e-3, 7);
  const SphereBvhTopology t = BuildSphereBvhTopology(99);
  SphereBvhSpheres s = MakeSphereBvhSpheres(t);
  RefitSphereBvh(t, x, 1e-3, s);
  std::vector<LinkPair> all(99 * 99);
  const int num_all = FindSelfCollisionsAllPairs(t, s, all.data(), static_cast<int>(all.size()));
  const auto all_sorted = Sorted(all, num_all);
  for (int capacity : {0, 2, 37, num_all - 1}) {
    std::vector<LinkPair> pairs(capacity + 4, LinkPair{-7, -7});
    const int found = FindSelfCollisions(t, s, pairs.data(), capacity);
    EXPECT_EQ(found, num_all);
    for (int k = capacity; k < capacity + 4; ++k) EXPECT_EQ(pairs[k].a, -7);  // nothing past it
    for (const auto& pair : Sorted(pairs, capacity)) {
      EXPECT_TRUE(std::binary_search(all_sorted.begin(), all_sorted.end(), pair));
    }
  }
}

// The broad phase keeps every pair the narrow phase needs: links closer than twice the
// inflation (exact double segment distance) are always among the pairs.
TEST(SphereBvh, FindsEveryLinkPairWithinTwiceTheInflation) {
  constexpr double kInflate_m = 20e-6;
  for (unsigned seed = 0; seed < 5; ++seed) {
    Eigen::Matrix3Xd x = RandomWalk(200, 50e-6, 40 + seed);
    x.colwise() += Eigen::Vector3d(0.25, 0.1, -0.05);  // away from the origin
    const SphereBvhTopology t = BuildSphereBvhTopology(199);
    SphereBvhSpheres s = MakeSphereBvhSpheres(t);
    RefitSphereBvh(t, x, kInflate_m, s);
    std::vector<LinkPair> pairs(199 * 199);
    const auto found = Sorted(pairs, FindSelfCollisions(t, s, pairs.data(), 199 * 199));
    int near = 0;
    for (int a = 0; a < 199; ++a) {
      for (int b = a + 2; b < 199; ++b) {
        const double d =
            ClosestSegmentSegment(x.col(a), x.col(a + 1), x.col(b), x.col(b + 1)).distance_m;
        if (d > 2.0 * kInflate_m) continue;
        ++near;
        EXPECT_TRUE(std::binary_search(found.begin(), found.end(), std::make_pair(a, b)))
            << a << "-" << b << " at " << d;
      }
    }
    EXPECT_GT(near, 0);
  }
}

}  // namespace
}  // namespace microdex::thread
