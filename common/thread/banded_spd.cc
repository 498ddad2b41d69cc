#include "common/thread/banded_spd.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "common/base/check.h"
#include "common/thread/vector_clones.h"

namespace microdex::thread {

BandedSpd::BandedSpd(int size, int half_bandwidth)
    : size_(size),
      p_(half_bandwidth),
      band_(Eigen::MatrixXd::Zero(half_bandwidth + 1, size)),
      upper_(Eigen::MatrixXd::Zero(half_bandwidth + 1, size)),
      inv_diag_(Eigen::VectorXd::Zero(size)),
      twist_(size) {
  MICRODEX_CHECK(size >= 1 && half_bandwidth >= 0);
}

// x and y are Refs so that a Map of the state is read in place (a const VectorXd& would
// build a heap temporary from it on every step).
namespace {

// Row i of the product for a half bandwidth P known at compile time, rows with a full band on
// both sides (P <= i < size - P): the same operations in the same order as the general loop.
template <int P>
void MultiplyFullRows(const double* band, const double* __restrict x, int size,
                      double* __restrict y) {
  for (int i = P; i < size - P; ++i) {
    double sum = band[static_cast<std::ptrdiff_t>(i) * (P + 1)] * x[i];
#pragma GCC unroll 8
    for (int j = i - P; j < i; ++j)
      sum += band[static_cast<std::ptrdiff_t>(j) * (P + 1) + i - j] * x[j];
    const double* col = band + static_cast<std::ptrdiff_t>(i) * (P + 1);
#pragma GCC unroll 8
    for (int d = 1; d <= P; ++d) sum += col[d] * x[i + d];
    y[i] = sum;
  }
}

}  // namespace

void BandedSpd::Multiply(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> y) const {
  const bool unrolled = p_ == 8 && size_ > 2 * p_;
  if (unrolled) MultiplyFullRows<8>(band_.data(), x.data(), size_, y.data());
  for (int i = 0; i < size_; ++i) {
    if (unrolled && i == p_) i = size_ - p_;  // the rows between are done
    double sum = band_(0, i) * x[i];
    const int lo = std::max(0, i - p_);
    for (int j = lo; j < i; ++j) sum += band_(i - j, j) * x[j];
    const int hi = std::min(size_ - 1, i + p_);
    for (int j = i + 1; j <= hi; ++j) sum += band_(j - i, i) * x[j];
    y[i] = sum;
  }
}

namespace {

// One column of the factorisation: the pivot's square root (false if the pivot is not
// positive), the m entries next to it scaled by its inverse (kept for the solves), and the
// m x m block they reach updated column by column: the column `c` steps away (at col + c * step)
// loses col[c + r] col[c], r = 0 .. m - c. Contiguous on both sides and element by element
// independent (vectorised in the callers' clones, the same bits at every width); only the
// pivots form a dependency chain. M > 0: m == M known at compile time (the loops unrolled:
// as loops of lengths 8 .. 1 they did not vectorise); M == 0: m at run time.
template <int M>
[[gnu::always_inline]] inline bool EliminateColumn(double* __restrict col, std::ptrdiff_t step,
                                                   int m_run, double* inv_diag) {
  const int m = M > 0 ? M : m_run;
  const double pivot = col[0];
  if (!(pivot > 0.0) || !std::isfinite(pivot)) return false;
  col[0] = std::sqrt(pivot);
  const double inv = 1.0 / col[0];
  *inv_diag = inv;
#pragma GCC unroll 8
  for (int d = 1; d <= m; ++d) col[d] *= inv;
#pragma GCC unroll 8
  for (int c = 1; c <= m; ++c) {
    const double lc = col[c];
    double* __restrict target = col + c * step;
#pragma GCC unroll 8
    for (int r = 0; r <= m - c; ++r) target[r] -= col[c + r] * lc;
  }
  return true;
}

// The top part, right-looking: columns *j .. end - 1 of the lower band storage, each subtracted
// from the block below it (A(j+c.., j+c) -= L(j+c.., j) L(j+c, j)). P > 0: only the columns with
// a full P x P block below (the loops unrolled), P == 0: any. Leaves *j at the next column.
template <int P>
MICRODEX_VECTOR_CLONES bool FactorizeDown(double* band, int rows, double* inv_diag, int size, int p,
                                          int end, int* j) {
  const std::ptrdiff_t stride = P > 0 ? P + 1 : rows;
  for (; *j < end && (P == 0 || *j + P < size); ++*j) {
    const int m = std::min(size - 1 - *j, p);
    if (!EliminateColumn<P>(band + *j * stride, stride, m, inv_diag + *j)) return false;
  }
  return true;
}

// The twisted part: columns *j down to twist of what the top part left (its Schur complement),
// eliminated upwards: U U^T with U upper triangular, in the upper band storage
// upper(d, j) = A(j - d, j) (column j of U contiguous, as L's columns are in the lower), each
// column subtracted from the block above it. P as for FactorizeDown.
template <int P>
MICRODEX_VECTOR_CLONES bool FactorizeUp(double* upper, int rows, double* inv_diag, int p, int twist,
                                        int* j) {
  const std::ptrdiff_t stride = P > 0 ? P + 1 : rows;
  for (; *j >= twist && (P == 0 || *j - P >= twist); --*j) {
    const int m = std::min(p, *j - twist);
    if (!EliminateColumn<P>(upper + *j * stride, -stride, m, inv_diag + *j)) return false;
  }
  return true;
}

}  // namespace

bool BandedSpd::Factorize(int twist) {
  twist_ = twist < 0 || twist > size_ ? size_ : twist;
  const int rows = p_ + 1;
  int j = 0;
  // The thread's system (half bandwidth 8, banded_spd.h) unrolled where the band is full.
  if (p_ == 8 && !FactorizeDown<8>(band_.data(), rows, inv_diag_.data(), size_, p_, twist_, &j))
    return false;
  if (!FactorizeDown<0>(band_.data(), rows, inv_diag_.data(), size_, p_, twist_, &j)) return false;
  if (twist_ >= size_) return true;
  // The Schur complement below the twist into the upper band storage.
  for (int c = twist_; c < size_; ++c) {
    for (int d = 0; d <= std::min(p_, c - twist_); ++d) upper_(d, c) = band_(d, c - d);
  }
  j = size_ - 1;
  if (p_ == 8 && !FactorizeUp<8>(upper_.data(), rows, inv_diag_.data(), p_, twist_, &j))
    return false;
  return FactorizeUp<0>(upper_.data(), rows, inv_diag_.data(), p_, twist_, &j);
}

namespace {

// BandedSpd::Solve for a half bandwidth P known at compile time (unrolled; the same operations
// in the same order), rows with a full band only: the forward pass's columns first .. size - P - 1
// (returns where it stopped) and the backward pass's rows size - P - 1 down to 0 (after the
// caller's rows above them).
template <int P>
MICRODEX_VECTOR_CLONES int ForwardFullColumns(const double* band, const double* inv_diag, int size,
                                              int first, int end, double* __restrict b) {
  int j = first;
  for (; j < end && j + P < size; ++j) {
    const double* col = band + static_cast<std::ptrdiff_t>(j) * (P + 1);
    b[j] *= inv_diag[j];
    const double yj = b[j];
#pragma GCC unroll 8
    for (int d = 1; d <= P; ++d) b[j + d] -= col[d] * yj;
  }
  return j;
}

template <int P>
void BackwardFullRows(const double* band, const double* inv_diag, int last, double* __restrict b) {
  for (int i = last; i >= 0; --i) {
    const double* col = band + static_cast<std::ptrdiff_t>(i) * (P + 1);
    double sum = b[i];
#pragma GCC unroll 8
    for (int d = 1; d <= P; ++d) sum -= col[d] * b[i + d];
    b[i] = sum * inv_diag[i];
  }
}

// The twisted part's U y = b, columns size - 1 down to twist + P (returns where it stopped), and
// U^T x = y, rows first .. size - 1 (each at least P below the twist), unrolled.
template <int P>
MICRODEX_VECTOR_CLONES int UpwardFullColumns(const double* upper, const double* inv_diag, int size,
                                             int twist, double* __restrict b) {
  int j = size - 1;
  for (; j - P >= twist; --j) {
    const double* col = upper + static_cast<std::ptrdiff_t>(j) * (P + 1);
    b[j] *= inv_diag[j];
    const double yj = b[j];
#pragma GCC unroll 8
    for (int d = 1; d <= P; ++d) b[j - d] -= col[d] * yj;
  }
  return j;
}

template <int P>
void DownwardFullRows(const double* upper, const double* inv_diag, int size, int first,
                      double* __restrict b) {
  for (int i = first; i < size; ++i) {
    const double* col = upper + static_cast<std::ptrdiff_t>(i) * (P + 1);
    double sum = b[i];
#pragma GCC unroll 8
    for (int d = 1; d <= P; ++d) sum -= col[d] * b[i - d];
    b[i] = sum * inv_diag[i];
  }
}

}  // namespace

void BandedSpd::Solve(Eigen::Ref<Eigen::VectorXd> b, int first_row) const {
  // The top part, L y = b by columns: each row is reduced by the solved rows above it in the
  // order of a row-by-row substitution (k ascending), with L's columns read contiguously; its
  // last columns reach into the twisted part's first rows.
  const int t = twist_;
  int start = std::max(0, first_row);
  if (p_ == 8)
    start = ForwardFullColumns<8>(band_.data(), inv_diag_.data(), size_, start, t, b.data());
  for (int j = start; j < t; ++j) {
    b[j] *= inv_diag_[j];
    const int m = std::min(size_ - 1 - j, p_);
    const double yj = b[j];
    for (int d = 1; d <= m; ++d) b[j + d] -= band_(d, j) * yj;
  }
  // The twisted part, U y = b from the bottom up, then U^T x = y from the twist down.
  int j = size_ - 1;
  if (p_ == 8) j = UpwardFullColumns<8>(upper_.data(), inv_diag_.data(), size_, t, b.data());
  for (; j >= t; --j) {
    b[j] *= inv_diag_[j];
    const int m = std::min(p_, j - t);
    const double yj = b[j];
    for (int d = 1; d <= m; ++d) b[j - d] -= upper_(d, j) * yj;
  }
  const int full_from = p_ == 8 ? std::min(size_, t + p_) : size_;
  for (int i = t; i < full_from; ++i) {
    double sum = b[i];
    const int m = std::min(p_, i - t);
    for (int d = 1; d <= m; ++d) sum -= upper_(d, i) * b[i - d];
    b[i] = sum * inv_diag_[i];
  }
  if (full_from < size_)
    DownwardFullRows<8>(upper_.data(), inv_diag_.data(), size_, full_from, b.data());
  // L^T x = y for the top part, the rows without a full band first.
  int i = t - 1;
  for (; i >= 0 && (p_ != 8 || i + p_ > size_ - 1); --i) {
    double sum = b[i];
    const int hi = std::min(size_ - 1, i + p_);
    for (int k = i + 1; k <= hi; ++k) sum -= band_(k - i, i) * b[k];
    b[i] = sum * inv_diag_[i];
  }
  if (i >= 0) BackwardFullRows<8>(band_.data(), inv_diag_.data(), i, b.data());
}

namespace {

// The multi-column solve of BandedSpd::SolveColumns in place on the row-major b (stride doubles
// per row), each row's update vectorised over its contiguous columns (vector_clones.h: the same
// bits on every machine). Above the twist t (L's rows) each row runs over the columns that
// start at or above it (first_rows ascending): forward because the others are still zero there,
// backward because a column's solution is wanted only from its first row down (and the rows
// below never read the rows above). Below the twist (U's rows) every column, and only the rows
// t .. end: b is zero below `end` on entry, and no row at or above `end` reads one below it.
MICRODEX_VECTOR_CLONES
void SubstituteColumns(const double* band, const double* upper, int band_rows,
                       const double* inv_diag, int size, int p, int t, int top, int end, double* b,
                       int stride, const int* first_rows, int cols) {
  auto row_at = [&](int i) { return b + static_cast<std::ptrdiff_t>(i) * stride; };
  auto at = [&](int d, int j) { return band[static_cast<std::ptrdiff_t>(j) * band_rows + d]; };
  auto up = [&](int d, int j) { return upper[static_cast<std::ptrdiff_t>(j) * band_rows + d]; };
  // L y = b over the top rows; the rows t .. t + p - 1 below them take the part of L's last
  // columns when they are reached.
  int active = 0;
  for (int i = top; i < t; ++i) {
    while (active < cols && first_rows[active] <= i) ++active;
    double* __restrict row = row_at(i);
    for (int k = std::max(top, i - p); k < i; ++k) {
      const double l = at(i - k, k);
      const double* __restrict other = row_at(k);
      for (int c = 0; c < active; ++c) row[c] -= l * other[c];
    }
    const double inv = inv_diag[i];
    for (int c = 0; c < active; ++c) row[c] *= inv;
  }
  // U y = b - L_21 y_1 from `end` up to the twist.
  for (int i = end; i >= t; --i) {
    double* __restrict row = row_at(i);
    for (int k = std::max(top, i - p); k < t; ++k) {
      const double l = at(i - k, k);
      const double* __restrict other = row_at(k);
      for (int c = 0; c < cols; ++c) row[c] -= l * other[c];
    }
    for (int k = std::min(end, i + p); k > i; --k) {  // in BandedSpd::Solve's order
      const double u = up(k - i, k);                  // U(i, k)
      const double* __restrict other = row_at(k);
      for (int c = 0; c < cols; ++c) row[c] -= u * other[c];
    }
    const double inv = inv_diag[i];
    for (int c = 0; c < cols; ++c) row[c] *= inv;
  }
  // U^T x = y from the twist down to `end`.
  for (int i = t; i <= end; ++i) {
    double* __restrict row = row_at(i);
    for (int k = i - 1; k >= std::max(t, i - p); --k) {  // in BandedSpd::Solve's order
      const double u = up(i - k, i);                     // U(k, i)
      const double* __restrict other = row_at(k);
      for (int c = 0; c < cols; ++c) row[c] -= u * other[c];
    }
    const double inv = inv_diag[i];
    for (int c = 0; c < cols; ++c) row[c] *= inv;
  }
  // L^T x = y - L_21^T x_2 from the twist up to `top`.
  active = cols;
  for (int i = std::min(t, size) - 1; i >= top; --i) {
    while (active > 0 && first_rows[active - 1] > i) --active;
    double* __restrict row = row_at(i);
    const int hi = std::min(size - 1, i + p);
    for (int k = i + 1; k <= hi; ++k) {
      const double l = at(k - i, i);
      const double* __restrict other = row_at(k);
      for (int c = 0; c < active; ++c) row[c] -= l * other[c];
    }
    const double inv = inv_diag[i];
    for (int c = 0; c < active; ++c) row[c] *= inv;
  }
}

// out[s] += weight * (dir0 a[s] + dir1 b[s] + dir2 c[s]) for s < count (element-wise: the same
// bits at every vector width).
MICRODEX_VECTOR_CLONES
void AddCombinedRows(const double* __restrict a, const double* __restrict b,
                     const double* __restrict c, const Eigen::Vector3d& dir, double weight,
                     int count, double* __restrict out) {
  const double d0 = dir[0], d1 = dir[1], d2 = dir[2];
  for (int s = 0; s < count; ++s) out[s] += weight * (d0 * a[s] + d1 * b[s] + d2 * c[s]);
}

// out[j] -= scale * row[j] for j < count (element-wise).
MICRODEX_VECTOR_CLONES
void SubtractScaledRow(const double* __restrict row, double scale, int count,
                       double* __restrict out) {
  for (int j = 0; j < count; ++j) out[j] -= scale * row[j];
}

}  // namespace

void BandedSpd::SolveColumns(RowMajorMatrix& b, int cols, const int* first_rows,
                             int last_row) const {
  MICRODEX_CHECK(b.rows() == size_ && cols <= b.cols());
  if (cols <= 0 || first_rows[0] >= size_) return;
  SubstituteColumns(band_.data(), upper_.data(), p_ + 1, inv_diag_.data(), size_, p_, twist_,
                    first_rows[0], SolvedEnd(last_row), b.data(), static_cast<int>(b.cols()),
                    first_rows, cols);
}

double NodeColumn::Dot(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double sum = 0.0;
  for (int k = 0; k < count; ++k) sum += weight[k] * dir.dot(x.segment<3>(3 * node[k]));
  return sum;
}

void NodeColumn::AddTo(double scale, Eigen::Ref<Eigen::VectorXd> x) const {
  for (int k = 0; k < count; ++k) x.segment<3>(3 * node[k]) += (scale * weight[k]) * dir;
}

namespace {

// In place Cholesky of the leading m x m block (lower triangle); false if not SPD.
bool CholeskyInPlace(Eigen::MatrixXd& s, int m) {
  for (int j = 0; j < m; ++j) {
    double d = s(j, j);
    for (int k = 0; k < j; ++k) d -= s(j, k) * s(j, k);
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    s(j, j) = std::sqrt(d);
    for (int i = j + 1; i < m; ++i) {
      double v = s(i, j);
      for (int k = 0; k < j; ++k) v -= s(i, k) * s(j, k);
      s(i, j) = v / s(j, j);
    }
  }
  return true;
}

void ForwardSolve(const Eigen::MatrixXd& l, int m, double* x) {
  for (int i = 0; i < m; ++i) {
    double v = x[i];
    for (int k = 0; k < i; ++k) v -= l(i, k) * x[k];
    x[i] = v / l(i, i);
  }
}

void BackSolve(const Eigen::MatrixXd& l, int m, double* x) {
  for (int i = m - 1; i >= 0; --i) {
    double v = x[i];
    for (int k = i + 1; k < m; ++k) v -= l(k, i) * x[k];
    x[i] = v / l(i, i);
  }
}

}  // namespace

LowRankSolver::LowRankSolver(int size, int max_columns)
    : size_(size),
      max_columns_(max_columns),
      y_(BandedSpd::RowMajorMatrix::Zero(size, std::max(1, max_columns))),
      order_(Eigen::VectorXi::Zero(std::max(1, max_columns))),
      slot_(Eigen::VectorXi::Zero(std::max(1, max_columns))),
      column_first_(Eigen::VectorXi::Zero(std::max(1, max_columns))),
      first_row_(Eigen::VectorXi::Zero(std::max(1, max_columns))),
      work_(Eigen::VectorXd::Zero(size)),
      h_(Eigen::MatrixXd::Zero(std::max(1, max_columns), std::max(1, max_columns))),
      x_ut_(BandedSpd::RowMajorMatrix::Zero(std::max(1, max_columns), std::max(1, max_columns))),
      small_(Eigen::VectorXd::Zero(std::max(1, max_columns))),
      row_(Eigen::VectorXd::Zero(std::max(1, max_columns))),
      correction_(Eigen::VectorXd::Zero(std::max(1, max_columns))) {
  MICRODEX_CHECK(size >= 1 && max_columns >= 0);
}

bool LowRankSolver::Prepare(const BandedSpd& factor, std::span<const NodeColumn> columns, int num_u,
                            const double* d) {
  const int m = static_cast<int>(columns.size());
  MICRODEX_CHECK(m <= max_columns_ && num_u >= 0 && num_u <= m && factor.size() == size_);
  factor_ = &factor;
  columns_ = columns;
  num_u_ = num_u;
  num_t_ = m - num_u;
  if (m == 0) return true;
  // Columns in the order of their first touched row (a column of grasped nodes only is zero
  // and goes last).
  int last = 0;
  for (int j = 0; j < m; ++j) {
    const NodeColumn& c = columns[j];
    int first = size_;
    for (int k = 0; k < c.count; ++k) {
      if (c.weight[k] == 0.0) continue;
      first = std::min(first, 3 * c.node[k]);
      last = std::max(last, 3 * c.node[k] + 2);
    }
    column_first_[j] = first;
    order_[j] = j;
  }
  std::sort(order_.data(), order_.data() + m, [&](int a, int b) {
    return column_first_[a] != column_first_[b] ? column_first_[a] < column_first_[b] : a < b;
  });
  for (int s = 0; s < m; ++s) {
    slot_[order_[s]] = s;
    first_row_[s] = column_first_[order_[s]];
  }
  const int top = first_row_[0];
  if (top < size_) y_.block(top, 0, factor.SolvedEnd(last) + 1 - top, m).setZero();
  for (int j = 0; j < m; ++j) {
    const NodeColumn& c = columns[j];
    for (int k = 0; k < c.count; ++k) {
      if (c.weight[k] == 0.0) continue;
      for (int r = 0; r < 3; ++r) y_(3 * c.node[k] + r, slot_[j]) += c.weight[k] * c.dir[r];
    }
  }
  factor.SolveColumns(y_, m, first_row_.data(), last);
  // H = V^T Y, symmetric, from the sparse columns (zero weights skipped). Y's column in slot s
  // is solved only from that column's first row down, so entry (i, j) is formed from the rows
  // of whichever of the two columns comes later in slot order (its rows lie at or below the
  // other's first row): row i of H over slots 0..slot_[i] is a combination of the (at most 12)
  // rows of Y that column i touches, formed over those slots at once (contiguous rows of the
  // row-major Y), and gives H(i, j) = H(j, i) for the columns j in those slots.
  for (int i = 0; i < m; ++i) {
    const NodeColumn& c = columns[i];
    const int count = slot_[i] + 1;
    row_.head(count).setZero();
    for (int k = 0; k < c.count; ++k) {
      if (c.weight[k] == 0.0) continue;
      const int row = 3 * c.node[k];
      AddCombinedRows(y_.row(row).data(), y_.row(row + 1).data(), y_.row(row + 2).data(), c.dir,
                      c.weight[k], count, row_.data());
    }
    for (int s = 0; s < count; ++s) {
      h_(i, order_[s]) = row_[s];
      h_(order_[s], i) = row_[s];
    }
  }
  // S = D^-1 + H_UU in place (lower triangle), then X = L_S^-1 H_UT.
  for (int i = 0; i < num_u_; ++i) {
    if (!(d[i] > 0.0)) return false;
    h_(i, i) += 1.0 / d[i];
  }
  if (!CholeskyInPlace(h_, num_u_)) return false;
  // Row by row over all of X's columns at once (X row-major; the same operations per element
  // as a forward substitution of each column).
  for (int i = 0; i < num_u_; ++i) {
    double* __restrict xi = x_ut_.row(i).data();
    for (int j = 0; j < num_t_; ++j) xi[j] = h_(num_u_ + j, i);  // H_UT(i, j) = H_TU(j, i)
    for (int k = 0; k < i; ++k) SubtractScaledRow(x_ut_.row(k).data(), h_(i, k), num_t_, xi);
    const double lii = h_(i, i);
    for (int j = 0; j < num_t_; ++j) xi[j] = xi[j] / lii;
  }
  return true;
}

bool LowRankSolver::SolveColumnSum(const double* coefficients, int first, int count) {
  work_.setZero();
  int top = size_;
  for (int j = 0; j < count; ++j) {
    const NodeColumn& c = columns_[first + j];
    for (int k = 0; k < c.count; ++k) {
      if (c.weight[k] == 0.0) continue;
      work_.segment<3>(3 * c.node[k]) += (coefficients[j] * c.weight[k]) * c.dir;
      top = std::min(top, 3 * c.node[k]);
    }
  }
  if (top >= size_) return false;
  factor_->Solve(work_, top);
  return true;
}

void LowRankSolver::CorrectSolution(Eigen::Ref<Eigen::VectorXd> x) {
  if (num_u_ == 0) return;
  // x -= A^-1 U S^-1 U^T x.
  for (int i = 0; i < num_u_; ++i) small_[i] = columns_[i].Dot(x);
  ForwardSolve(h_, num_u_, small_.data());
  BackSolve(h_, num_u_, small_.data());
  for (int i = 0; i < num_u_; ++i) small_[i] = -small_[i];
  if (SolveColumnSum(small_.data(), 0, num_u_)) x += work_;
}

void LowRankSolver::BeginCorrection(const Eigen::Ref<const Eigen::VectorXd>& x) {
  for (int i = 0; i < num_u_; ++i) correction_[i] = columns_[i].Dot(x);
  ForwardSolve(h_, num_u_, correction_.data());
  BackSolve(h_, num_u_, correction_.data());
}

double LowRankSolver::CorrectionDot(int t) const {
  // T_t^T A^-1 U s = (H_TU s)_t; H_TU is below the factorised block of h_.
  double sum = 0.0;
  for (int i = 0; i < num_u_; ++i) sum += h_(num_u_ + t, i) * correction_[i];
  return sum;
}

void LowRankSolver::FinishCorrection(const Eigen::Ref<const Eigen::VectorXd>& p,
                                     Eigen::Ref<Eigen::VectorXd> x) {
  // x - A^-1 U s + A^-1 (T p - U S^-1 H_UT p) = x + A^-1 (T p - U (s + L_S^-T X p)).
  for (int k = 0; k < num_u_; ++k) small_[k] = RowDot(k, p);
  BackSolve(h_, num_u_, small_.data());
  for (int k = 0; k < num_u_; ++k) small_[k] = -(small_[k] + correction_[k]);
  for (int j = 0; j < num_t_; ++j) small_[num_u_ + j] = p[j];
  if (SolveColumnSum(small_.data(), 0, num_u_ + num_t_)) x += work_;
}

double LowRankSolver::RowDot(int k, const Eigen::Ref<const Eigen::VectorXd>& p) const {
  // Summed in index order (a vectorised dot would sum in another order).
  if (num_t_ == 0) return 0.0;
  const double* row = x_ut_.row(k).data();
  double sum = row[0] * p[0];
  for (int j = 1; j < num_t_; ++j) sum += row[j] * p[j];
  return sum;
}

void LowRankSolver::Delassus(Eigen::MatrixXd& g) {
  // G = H_TT - X^T X, X = L_S^-1 H_UT: row i of G's lower triangle at once, X's rows
  // (contiguous, row-major) subtracted in k order, element by element.
  for (int i = 0; i < num_t_; ++i) {
    double* acc = row_.data();
    for (int j = 0; j <= i; ++j) acc[j] = h_(num_u_ + i, num_u_ + j);
    for (int k = 0; k < num_u_; ++k) {
      SubtractScaledRow(x_ut_.row(k).data(), x_ut_(k, i), i + 1, acc);
    }
    for (int j = 0; j <= i; ++j) {
      g(i, j) = acc[j];
      g(j, i) = acc[j];
    }
  }
}

void LowRankSolver::AddResponse(const Eigen::Ref<const Eigen::VectorXd>& p,
                                Eigen::Ref<Eigen::VectorXd> x) {
  if (num_t_ == 0) return;
  // (A + U D U^T)^-1 T p = A^-1 (T p - U S^-1 H_UT p), with S^-1 H_UT p = L_S^-T X p.
  for (int k = 0; k < num_u_; ++k) small_[k] = RowDot(k, p);
  BackSolve(h_, num_u_, small_.data());
  for (int k = 0; k < num_u_; ++k) small_[k] = -small_[k];
  for (int j = 0; j < num_t_; ++j) small_[num_u_ + j] = p[j];
  if (SolveColumnSum(small_.data(), 0, num_u_ + num_t_)) x += work_;
}

}  // namespace microdex::thread
