// Banded Cholesky against Eigen's dense LLT.
#include "common/thread/banded_spd.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

namespace microdex::thread {
namespace {

TEST(BandedSpd, SolveMatchesDenseCholesky) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 60, p = 8;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  BandedSpd band(n, p);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - p); j < i; ++j) {
      const double v = u(rng);
      dense(i, j) = dense(j, i) = v;
      band.At(i, j) = v;
    }
    dense(i, i) = 2.0 * p + 1.0 + u(rng);  // diagonally dominant: SPD
    band.At(i, i) = dense(i, i);
  }
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = u(rng);
  Eigen::VectorXd y(n);
  band.Multiply(b, y);
  EXPECT_LT((y - dense * b).norm(), 1e-12 * y.norm());
  const Eigen::VectorXd expected = dense.llt().solve(b);
  ASSERT_TRUE(band.Factorize());
  Eigen::VectorXd x = b;
  band.Solve(x);
  EXPECT_LT((x - expected).norm(), 1e-12 * expected.norm());
}

TEST(BandedSpd, RejectsIndefiniteMatrix) {
  BandedSpd band(3, 1);
  band.At(0, 0) = 1.0;
  band.At(1, 0) = 2.0;
  band.At(1, 1) = 1.0;
  band.At(2, 2) = 1.0;
  EXPECT_FALSE(band.Factorize());
}

}  // namespace
}  // namespace microdex::thread
