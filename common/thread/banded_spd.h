#pragma once
// Symmetric positive definite band matrix with an in-place Cholesky factorisation.
//
// The linearly implicit thread step solves (M + h C + h^2 K) dv = b where K couples each node
// to the nodes two links away at most (stretch: one, bending: two), so the 3N x 3N matrix has a
// half bandwidth of 8. Eigen has no dense banded factorisation and its sparse Cholesky builds
// temporaries while factorising; this one works in storage sized once, O(N p^2) per solve.

#include <Eigen/Core>

namespace microdex::thread {

class BandedSpd {
 public:
  BandedSpd() = default;
  BandedSpd(int size, int half_bandwidth);

  int size() const { return size_; }
  int half_bandwidth() const { return p_; }

  void SetZero() { band_.setZero(); }
  // A(i, j) for |i - j| <= p (symmetric: either triangle may be given).
  double& At(int i, int j) { return i >= j ? band_(i - j, i) : band_(j - i, j); }
  double At(int i, int j) const { return i >= j ? band_(i - j, i) : band_(j - i, j); }
  // Adds a 3x3 block at block row a, block column b (|a - b| small enough for the band). Only
  // the lower triangle is written, so add each off-diagonal block once with a > b.
  void AddBlock(int a, int b, const Eigen::Matrix3d& block);

  // y = A x using the (unfactorised) band.
  void Multiply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const;

  // In place A = L L^T. Returns false (and leaves garbage) on a non-positive pivot.
  bool Factorize();
  // Solves L L^T x = b in place, after Factorize().
  void Solve(Eigen::VectorXd& b) const;

 private:
  int size_ = 0;
  int p_ = 0;
  Eigen::MatrixXd band_;  // band_(d, i) = A(i, i - d), d in [0, p]
};

}  // namespace microdex::thread
