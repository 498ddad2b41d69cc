// The link-collider gap's cheap lower bound (the boxes' distance) against the exact gap.
#include "common/thread/colliders.h"

#include <gtest/gtest.h>

#include <random>

namespace microdex::thread {
namespace {

// Random links near random spheres, capsules and planes, from touching and overlapping to
// far: the bound never exceeds the exact gap (a skipped link is never a contact), equals it
// for planes, and is positive for links far from the collider (it skips them).
TEST(LinkColliderGapLowerBound, NeverExceedsTheExactGapAndSeparatesFarLinks) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double r = 12.5e-6;
  int far = 0, far_skipped = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double scale = trial % 3 == 0 ? 1e-4 : 2e-3;  // a third packed close together
    const Eigen::Vector3d x0 = scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Vector3d x1 = x0 + 1e-4 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Vector3d c0 = scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
    Collider col;
    switch (trial % 3) {
      case 0:
        col = Collider::Sphere(c0, 1e-4 * (1.0 + u(rng)));
        break;
      case 1:
        col = Collider::Capsule(c0, c0 + 1e-3 * Eigen::Vector3d(u(rng), u(rng), u(rng)),
                                1e-4 * (1.0 + u(rng)));
        break;
      default:
        col = Collider::Plane(c0, Eigen::Vector3d(u(rng), u(rng), u(rng) + 2.0));
        break;
    }
    const double exact = CalcLinkColliderGap(col, x0, x1, r).gap_m;
    const double bound = LinkColliderGapLowerBound(col, x0, x1, r);
    ASSERT_LE(bound, exact + 1e-15) << "trial " << trial;
    if (col.kind == ColliderKind::kPlane) {
      EXPECT_EQ(bound, exact) << "trial " << trial;
    }
    if (col.kind != ColliderKind::kPlane && exact > 1e-3) {
      ++far;
      if (bound > 0.0) ++far_skipped;
    }
  }
  ASSERT_GT(far, 100);
  EXPECT_GT(far_skipped, far * 9 / 10);
}

}  // namespace
}  // namespace microdex::thread
