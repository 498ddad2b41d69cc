// Banded Cholesky and its low-rank update against Eigen's dense LLT.
#include "common/thread/banded_spd.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

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

// The multi-column solve of sparse columns (vectorised, its build chosen by the CPU) gives each
// column exactly the bits of the single-vector solve: the same products and subtractions in the
// same order, only several columns at once. Re-simulation of a recording depends on it.
TEST(BandedSpd, SolveColumnsEqualsSingleSolvesBitForBit) {
  const int n = 150, p = 8, cols = 37;  // odd: vector tails of every width
  // Twists: none, above every column, among the first rows, below them, at the last rows.
  for (const int twist : {-1, 0, 40, 90, 120, 147}) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    BandedSpd band(n, p);
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - p); j < i; ++j) band.At(i, j) = u(rng);
      band.At(i, i) = 2.0 * p + 1.0 + u(rng);
    }
    ASSERT_TRUE(band.Factorize(twist));
    std::vector<int> first(cols);
    for (int j = 0; j < cols; ++j) first[j] = std::uniform_int_distribution<int>(10, 100)(rng);
    std::sort(first.begin(), first.end());
    int last = 0;
    BandedSpd::RowMajorMatrix b = BandedSpd::RowMajorMatrix::Zero(n, cols + 3);  // wider: stride
    for (int j = 0; j < cols; ++j) {
      for (int r = first[j]; r < first[j] + 4; ++r) b(r, j) = u(rng);
      b(first[j] + 20, j) = u(rng);  // a second node further down
      last = std::max(last, first[j] + 20);
    }
    const BandedSpd::RowMajorMatrix rhs = b;
    band.SolveColumns(b, cols, first.data(), last);
    const int end = band.SolvedEnd(last);
    EXPECT_GE(end, last);
    for (int j = 0; j < cols; ++j) {
      Eigen::VectorXd x = rhs.col(j);
      band.Solve(x, first[j]);
      // Each column is solved from its own first row down to SolvedEnd; compare those rows.
      for (int r = first[j]; r <= end; ++r) {
        ASSERT_EQ(b(r, j), x[r]) << "twist " << twist << " column " << j << " row " << r;
      }
    }
  }
}

// A twisted factor solves the same system as the plain one (to rounding), wherever the twist.
TEST(BandedSpd, TwistedFactorSolvesTheSameSystem) {
  const int n = 60, p = 8;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  BandedSpd band(n, p);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - p); j < i; ++j) {
      a(i, j) = a(j, i) = band.At(i, j) = u(rng);
    }
    a(i, i) = band.At(i, i) = 2.0 * p + 1.0 + u(rng);
  }
  Eigen::VectorXd rhs(n);
  for (int i = 0; i < n; ++i) rhs[i] = u(rng);
  const Eigen::VectorXd reference = a.llt().solve(rhs);
  for (const int twist : {-1, 0, 1, 7, 8, 30, 52, 59, 60}) {
    BandedSpd factor = band;
    ASSERT_TRUE(factor.Factorize(twist));
    EXPECT_EQ(factor.twist(), twist < 0 ? n : twist);
    Eigen::VectorXd x = rhs;
    factor.Solve(x);
    EXPECT_LT((x - reference).norm(), 1e-13 * reference.norm()) << "twist " << twist;
    // A sparse right-hand side from row 25.
    Eigen::VectorXd sparse = Eigen::VectorXd::Zero(n);
    sparse.segment(25, 6) = rhs.segment(25, 6);
    const Eigen::VectorXd sparse_reference = a.llt().solve(sparse);
    factor.Solve(sparse, 25);
    EXPECT_LT((sparse - sparse_reference).norm(), 1e-13 * sparse_reference.norm())
        << "twist " << twist;
  }
  // A non-positive pivot is found below the twist too.
  BandedSpd bad = band;
  bad.At(n - 1, n - 1) = -1.0;
  EXPECT_FALSE(bad.Factorize(30));
}

// The low-rank solver (Woodbury on the banded factor, and the Delassus operator of further
// columns) against a dense LLT of the full matrix A + U D U^T.
TEST(LowRankSolver, MatchesDenseCholeskyOfTheFullMatrix) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> node(0, 19);
  const int nodes = 20, n = 3 * nodes, p = 8;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  BandedSpd band(n, p);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - p); j < i; ++j) {
      const double v = u(rng);
      a(i, j) = a(j, i) = v;
      band.At(i, j) = v;
    }
    a(i, i) = 2.0 * p + 1.0 + u(rng);
    band.At(i, i) = a(i, i);
  }
  // Five pair columns (4 nodes, weights summing to zero as a contact's do) with weights d, then
  // six further columns (two nodes, like object contacts).
  const int num_u = 5, num_t = 6;
  std::vector<NodeColumn> cols(num_u + num_t);
  Eigen::MatrixXd dense_cols = Eigen::MatrixXd::Zero(n, num_u + num_t);
  std::vector<double> d(num_u);
  for (int j = 0; j < num_u + num_t; ++j) {
    NodeColumn& c = cols[j];
    c.count = j < num_u ? 4 : 2;
    const double s = 0.5 * (1.0 + u(rng)), t = 0.5 * (1.0 + u(rng));
    const double w4[4] = {1.0 - s, s, -(1.0 - t), -t};
    const double w2[2] = {1.0 - s, s};
    for (int k = 0; k < c.count; ++k) {
      c.node[k] = node(rng);
      c.weight[k] = c.count == 4 ? w4[k] : w2[k];
    }
    c.dir = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    for (int k = 0; k < c.count; ++k) {
      dense_cols.block<3, 1>(3 * c.node[k], j) += c.weight[k] * c.dir;
    }
    if (j < num_u) d[j] = std::pow(10.0, 3.0 * u(rng));  // 1e-3 .. 1e3: stiff and soft pairs
  }
  const Eigen::MatrixXd uu = dense_cols.leftCols(num_u);
  const Eigen::MatrixXd tt = dense_cols.rightCols(num_t);
  Eigen::MatrixXd full = a;
  for (int j = 0; j < num_u; ++j) full += d[j] * uu.col(j) * uu.col(j).transpose();
  const Eigen::LLT<Eigen::MatrixXd> llt(full);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = u(rng);
  const Eigen::VectorXd expected = llt.solve(b);

  // Plain and twisted factors (above, among and below the columns' rows).
  for (const int twist : {-1, 0, 21, 30, 45, 59}) {
    SCOPED_TRACE(twist);
    BandedSpd factor = band;
    ASSERT_TRUE(factor.Factorize(twist));
    LowRankSolver solver(n, num_u + num_t);
    ASSERT_TRUE(solver.Prepare(factor, cols, num_u, d.data()));
    Eigen::VectorXd x = b;
    factor.Solve(x);
    solver.CorrectSolution(x);
    EXPECT_LT((x - expected).norm(), 1e-10 * expected.norm());

    Eigen::MatrixXd g(num_t, num_t);
    solver.Delassus(g);
    const Eigen::MatrixXd g_dense = tt.transpose() * llt.solve(tt);
    EXPECT_LT((g - g_dense).norm(), 1e-10 * g_dense.norm());

    Eigen::VectorXd impulse(num_t);
    for (int j = 0; j < num_t; ++j) impulse[j] = u(rng);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
    solver.AddResponse(impulse, y);
    const Eigen::VectorXd y_dense = llt.solve(tt * impulse);
    EXPECT_LT((y - y_dense).norm(), 1e-10 * y_dense.norm());
    // The correction and the response in one solve, from A^-1 b: the same as both in turn.
    Eigen::VectorXd fused = b;
    factor.Solve(fused);
    solver.BeginCorrection(fused);
    for (int j = 0; j < num_t; ++j) {
      EXPECT_NEAR(tt.col(j).dot(fused) - solver.CorrectionDot(j), tt.col(j).dot(expected),
                  1e-10 * expected.norm() * tt.col(j).norm());
    }
    solver.FinishCorrection(impulse, fused);
    const Eigen::VectorXd fused_dense = expected + y_dense;
    EXPECT_LT((fused - fused_dense).norm(), 1e-10 * fused_dense.norm());
  }
  // NodeColumn's own products agree with the dense columns.
  EXPECT_NEAR(cols[0].Dot(b), uu.col(0).dot(b), 1e-12);
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
