// The iterative solvers against dense references: DIC through Eisenstat's trick against plain
// PCG with the same preconditioner written out, breakdowns, warm starts and the stopping rule.

#include "common/fem/cg_solver.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

namespace microdex::fem {
namespace {

// Full CSR with sorted columns, from a dense symmetric matrix (entries exactly zero are left
// out of the pattern).
struct Csr {
  std::vector<int> row_ptr, cols, diag;
  std::vector<double> vals;
  CsrView View() const {
    return {static_cast<int>(diag.size()), row_ptr.data(), cols.data(), vals.data(), diag.data()};
  }
};
Csr ToCsr(const Eigen::MatrixXd& a) {
  Csr m;
  m.row_ptr.push_back(0);
  for (int i = 0; i < a.rows(); ++i) {
    for (int j = 0; j < a.cols(); ++j) {
      if (a(i, j) == 0 && i != j) continue;
      if (i == j) m.diag.push_back(static_cast<int>(m.cols.size()));
      m.cols.push_back(j);
      m.vals.push_back(a(i, j));
    }
    m.row_ptr.push_back(static_cast<int>(m.cols.size()));
  }
  return m;
}

// The P1 stiffness of a side × side grid of right triangles (7-point stencil, the tissue's
// element pattern), Dirichlet on the border, plus penalty springs k λλᵀ on random triangles:
// positive off-diagonal entries, so SPD but no M-matrix, as K_ff + penalty in a tissue step.
Eigen::MatrixXd Stiffness(int side, double spring, std::mt19937& rng) {
  const int n = side * side;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  auto id = [side](int x, int y) {
    return (x < 0 || y < 0 || x >= side || y >= side) ? -1 : y * side + x;
  };
  const double k[3][3] = {{1, -0.5, -0.5}, {-0.5, 0.5, 0}, {-0.5, 0, 0.5}};  // right angle first
  for (int y = -1; y < side; ++y) {
    for (int x = -1; x < side; ++x) {
      const int tri[2][3] = {{id(x, y), id(x + 1, y), id(x, y + 1)},
                             {id(x + 1, y + 1), id(x, y + 1), id(x + 1, y)}};
      for (const auto& t : tri) {
        for (int p = 0; p < 3; ++p) {
          for (int q = 0; q < 3; ++q) {
            if (t[p] >= 0 && t[q] >= 0) a(t[p], t[q]) += k[p][q];
          }
        }
      }
    }
  }
  std::uniform_real_distribution<double> u(0.05, 0.9);
  for (int s = 0; s < n / 8; ++s) {
    const int x = static_cast<int>(rng() % (side - 1)), y = static_cast<int>(rng() % (side - 1));
    const int nodes[3] = {id(x, y), id(x + 1, y), id(x, y + 1)};
    const double l0 = u(rng), l1 = (1 - l0) * u(rng);
    const double lambda[3] = {l0, l1, 1 - l0 - l1};
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) a(nodes[p], nodes[q]) += spring * lambda[p] * lambda[q];
  }
  return a;
}

// PCG with M = (D + L) D⁻¹ (D + Lᵀ) applied by a dense solve: the textbook algorithm that
// Eisenstat's form must reproduce.
int ReferenceDicPcg(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double tol,
                    double relaxation, Eigen::VectorXd& x) {
  const int n = static_cast<int>(a.rows());
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) {
    d[i] = a(i, i);
    for (int j = 0; j < i; ++j) d[i] -= a(i, j) * a(i, j) / d[j];
  }
  d *= relaxation;
  Eigen::MatrixXd lower = Eigen::MatrixXd(a.triangularView<Eigen::StrictlyLower>());
  lower.diagonal() = d;
  const Eigen::MatrixXd m = lower * d.cwiseInverse().asDiagonal() * lower.transpose();
  const Eigen::LLT<Eigen::MatrixXd> mf(m);
  Eigen::VectorXd r = b - a * x, z = mf.solve(r), p = z;
  double rz = r.dot(z);
  int it = 0;
  while (r.norm() > tol * b.norm() && it < 10 * n) {
    const Eigen::VectorXd q = a * p;
    const double alpha = rz / p.dot(q);
    x += alpha * p;
    r -= alpha * q;
    ++it;
    if (r.norm() <= tol * b.norm()) break;
    z = mf.solve(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return it;
}

TEST(CgSolver, EisenstatDicMatchesPcgWithTheSamePreconditioner) {
  std::mt19937 rng(7);
  for (int side : {6, 13, 24}) {
    for (double spring : {0.0, 3.0, 30.0}) {
      const Eigen::MatrixXd a = Stiffness(side, spring, rng);
      const int n = static_cast<int>(a.rows());
      const Csr csr = ToCsr(a);
      CgWorkspace ws = MakeCgWorkspace(n, static_cast<int>(csr.cols.size()));
      const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
      const Eigen::VectorXd exact = a.ldlt().solve(b);
      for (double relaxation : {1.0, 0.8}) {
        ASSERT_TRUE(FactorDic(csr.View(), ws, relaxation)) << side << " " << spring;
        for (double tol : {1e-4, 1e-8, 1e-11}) {
          // From zero and from a warm start near the solution.
          for (double start : {0.0, 1e-3}) {
            Eigen::VectorXd x0 = exact + start * Eigen::VectorXd::Random(n).cwiseProduct(exact);
            if (start == 0) x0.setZero();
            Eigen::VectorXd x_ref = x0, x = x0;
            const int it_ref = ReferenceDicPcg(a, b, tol, relaxation, x_ref);
            const CgResult r =
                SolveCg(csr.View(), b.data(), x.data(), Preconditioner::kDic, tol, 10 * n, ws);
            SCOPED_TRACE(testing::Message()
                         << "side " << side << " spring " << spring << " tol " << tol << " start "
                         << start << " relaxation " << relaxation);
            EXPECT_TRUE(r.converged);
            // Same Krylov method: the same iterations, up to the rounding of the stopping test.
            EXPECT_LE(std::abs(r.iterations - it_ref), 1) << r.iterations << " vs " << it_ref;
            const double true_residual = (b - a * x).norm() / b.norm();
            EXPECT_LE(true_residual, 1.5 * tol);
            EXPECT_NEAR(r.relative_residual, true_residual, 0.2 * tol + 1e-14);
            EXPECT_LE((x - exact).norm(), 10 * tol * a.ldlt().solve(b).norm() * n);
          }
        }
      }
    }
  }
}

TEST(CgSolver, EisenstatDicTakesNoMoreIterationsThanJacobi) {
  std::mt19937 rng(11);
  const Eigen::MatrixXd a = Stiffness(32, 30.0, rng);
  const int n = static_cast<int>(a.rows());
  const Csr csr = ToCsr(a);
  CgWorkspace ws = MakeCgWorkspace(n, static_cast<int>(csr.cols.size()));
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  ASSERT_TRUE(FactorJacobi(csr.View(), ws));
  const int jacobi =
      SolveCg(csr.View(), b.data(), x.data(), Preconditioner::kJacobi, 1e-8, 10 * n, ws).iterations;
  x.setZero();
  ASSERT_TRUE(FactorDic(csr.View(), ws));
  const CgResult dic =
      SolveCg(csr.View(), b.data(), x.data(), Preconditioner::kDic, 1e-8, 10 * n, ws);
  EXPECT_TRUE(dic.converged);
  EXPECT_LT(dic.iterations, jacobi / 2 + 1) << dic.iterations << " vs Jacobi " << jacobi;
}

TEST(CgSolver, DicBreaksDownWhereIc0DoesNot) {
  // SPD (eigenvalues 2.6, 0.2, 0.2) but far from an M-matrix: d₃ = 1 − a² − a²/(1 − a²) < 0.
  Eigen::MatrixXd a(3, 3);
  a << 1, 0.8, 0.8, 0.8, 1, 0.8, 0.8, 0.8, 1;
  const Csr csr = ToCsr(a);
  CgWorkspace ws = MakeCgWorkspace(3, 9);
  EXPECT_FALSE(FactorDic(csr.View(), ws));
  EXPECT_TRUE(FactorIc0(csr.View(), ws));  // a full pattern: IC(0) is the exact Cholesky
}

TEST(CgSolver, ExactWarmStartTakesNoIterationAndZeroRightHandSideGivesZero) {
  std::mt19937 rng(3);
  const Eigen::MatrixXd a = Stiffness(10, 1.0, rng);
  const int n = static_cast<int>(a.rows());
  const Csr csr = ToCsr(a);
  CgWorkspace ws = MakeCgWorkspace(n, static_cast<int>(csr.cols.size()));
  ASSERT_TRUE(FactorDic(csr.View(), ws));
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
  Eigen::VectorXd x = a.ldlt().solve(b);
  const Eigen::VectorXd before = x;
  const CgResult r = SolveCg(csr.View(), b.data(), x.data(), Preconditioner::kDic, 1e-8, 100, ws);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(x, before);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  const CgResult z =
      SolveCg(csr.View(), zero.data(), x.data(), Preconditioner::kDic, 1e-8, 100, ws);
  EXPECT_TRUE(z.converged);
  EXPECT_EQ(x.norm(), 0.0);
}

TEST(CgSolver, EisenstatDicReportsNonConvergenceAndNaN) {
  std::mt19937 rng(5);
  const Eigen::MatrixXd a = Stiffness(16, 1.0, rng);
  const int n = static_cast<int>(a.rows());
  const Csr csr = ToCsr(a);
  CgWorkspace ws = MakeCgWorkspace(n, static_cast<int>(csr.cols.size()));
  ASSERT_TRUE(FactorDic(csr.View(), ws));
  Eigen::VectorXd b = Eigen::VectorXd::Random(n), x = Eigen::VectorXd::Zero(n);
  const CgResult few = SolveCg(csr.View(), b.data(), x.data(), Preconditioner::kDic, 1e-12, 3, ws);
  EXPECT_FALSE(few.converged);
  EXPECT_EQ(few.iterations, 3);
  EXPECT_GT(few.relative_residual, 1e-12);
  EXPECT_NEAR(few.relative_residual, (b - a * x).norm() / b.norm(), 1e-9);
  b[n / 2] = std::nan("");
  x.setZero();
  const CgResult bad = SolveCg(csr.View(), b.data(), x.data(), Preconditioner::kDic, 1e-8, 100, ws);
  EXPECT_FALSE(bad.converged);
}

}  // namespace
}  // namespace microdex::fem
