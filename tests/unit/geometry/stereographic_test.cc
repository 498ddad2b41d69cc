#include "common/geometry/stereographic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace microdex::geometry {
namespace {

TEST(StereographicTest, LiftLiesOnS3AndProjectsBack) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n;
  for (int i = 0; i < 1000; ++i) {
    const double scale = std::pow(10.0, 4 * (i % 7) / 6.0 - 2);  // 1e-2 … 1e2
    const Eigen::Vector3d x = scale * Eigen::Vector3d(n(rng), n(rng), n(rng));
    const Eigen::Vector4d X = LiftToS3(x);
    EXPECT_NEAR(X.squaredNorm(), 1.0, 1e-14);
    EXPECT_LE((ProjectFromS3(X) - x).norm(), 1e-12 * (1 + x.squaredNorm()));
  }
}

TEST(StereographicTest, LiftTangentMatchesFiniteDifference) {
  const Eigen::Vector3d x(0.3, -1.2, 0.7), v(0.5, 0.1, -0.4);
  const double h = 1e-6;
  const Eigen::Vector4d fd = (LiftToS3(x + h * v) - LiftToS3(x - h * v)) / (2 * h);
  EXPECT_LE((LiftTangentToS3(x, v) - fd).norm(), 1e-9);
  // Tangent to S³ at the lifted point.
  EXPECT_NEAR(LiftTangentToS3(x, v).dot(LiftToS3(x)), 0.0, 1e-15);
}

// Appendix B: after scaling by λ = 1/√(R² − r²), the torus (4.1) is the projection of (4.4)
// with α = r̃, and G > 0 exactly inside the tube. Checked against the distance to the core
// circle computed directly, on points inside, outside and near the wall.
TEST(StereographicTest, AppendixBScalingLiftsTheTorusToTheQuadric) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const double beta : {1e-3, 0.1, 0.5, 0.9, 0.999}) {
    const double R = 7e-3, r = beta * R;
    const TorusLiftScale s = CalcTorusLiftScale(R, r);
    EXPECT_NEAR(s.alpha * s.alpha, beta * beta / (1 - beta * beta),
                1e-12 * s.alpha * s.alpha);  // (B.5)
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector3d x = 2.5 * R * Eigen::Vector3d(u(rng), u(rng), 0.5 * u(rng));
      const double w = std::hypot(x.x(), x.y());
      const double d = std::hypot(w - R, x.z());
      const Eigen::Vector3d xs = s.lambda * x;
      const double G = EvalLiftedTorus(s.alpha, LiftToS3(xs));
      // (4.1) in scaled units, and the factorisation g = (d² − r²)(d² − r² + 4Rw).
      const double Rs = s.lambda * R, rs = s.lambda * r;
      const double rho2 = xs.squaredNorm();
      const double g =
          std::pow(rho2 + Rs * Rs - rs * rs, 2) - 4 * Rs * Rs * xs.head<2>().squaredNorm();
      EXPECT_NEAR(g, -std::pow(rho2 + 1, 2) * G,
                  1e-11 * std::pow(rho2 + 1, 2) * (1 + s.alpha * s.alpha));
      if (std::abs(d - r) > 1e-9 * R) {
        EXPECT_EQ(G > 0, d < r) << "beta " << beta << " d " << d;
      }
    }
  }
}

}  // namespace
}  // namespace microdex::geometry
