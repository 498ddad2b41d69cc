#include "common/thread/banded_spd.h"

#include <algorithm>
#include <cmath>

#include "common/base/check.h"

namespace microdex::thread {

BandedSpd::BandedSpd(int size, int half_bandwidth)
    : size_(size), p_(half_bandwidth), band_(Eigen::MatrixXd::Zero(half_bandwidth + 1, size)) {
  MICRODEX_CHECK(size >= 1 && half_bandwidth >= 0);
}

void BandedSpd::AddBlock(int a, int b, const Eigen::Matrix3d& block) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const int i = 3 * a + r;
      const int j = 3 * b + c;
      if (i < j) continue;
      band_(i - j, i) += block(r, c);
    }
  }
}

// x and y are Refs so that a Map of the state is read in place (a const VectorXd& would
// build a heap temporary from it on every step).
void BandedSpd::Multiply(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> y) const {
  for (int i = 0; i < size_; ++i) {
    double sum = band_(0, i) * x[i];
    const int lo = std::max(0, i - p_);
    for (int j = lo; j < i; ++j) sum += band_(i - j, i) * x[j];
    const int hi = std::min(size_ - 1, i + p_);
    for (int j = i + 1; j <= hi; ++j) sum += band_(j - i, j) * x[j];
    y[i] = sum;
  }
}

bool BandedSpd::Factorize() {
  for (int i = 0; i < size_; ++i) {
    const int lo = std::max(0, i - p_);
    for (int j = lo; j <= i; ++j) {
      double sum = band_(i - j, i);
      const int klo = std::max(lo, j - p_);
      for (int k = klo; k < j; ++k) sum -= band_(i - k, i) * band_(j - k, j);
      if (j < i) {
        band_(i - j, i) = sum / band_(0, j);
      } else {
        if (!(sum > 0.0) || !std::isfinite(sum)) return false;
        band_(0, i) = std::sqrt(sum);
      }
    }
  }
  return true;
}

void BandedSpd::Solve(Eigen::VectorXd& b) const {
  for (int i = 0; i < size_; ++i) {  // L y = b
    double sum = b[i];
    const int lo = std::max(0, i - p_);
    for (int k = lo; k < i; ++k) sum -= band_(i - k, i) * b[k];
    b[i] = sum / band_(0, i);
  }
  for (int i = size_ - 1; i >= 0; --i) {  // L^T x = y
    double sum = b[i];
    const int hi = std::min(size_ - 1, i + p_);
    for (int k = i + 1; k <= hi; ++k) sum -= band_(k - i, k) * b[k];
    b[i] = sum / band_(0, i);
  }
}

}  // namespace microdex::thread
