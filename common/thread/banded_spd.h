#pragma once
// Symmetric positive definite band matrix with an in-place Cholesky factorisation.
//
// The linearly implicit thread step solves (M + h C + h^2 K) dv = b where K couples each node
// to the nodes two links away at most (stretch: one, bending: two), so the 3N x 3N matrix has a
// half bandwidth of 8. Eigen has no dense banded factorisation and its sparse Cholesky builds
// temporaries while factorising; this one works in storage sized once, O(N p^2) per solve.

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <span>

namespace microdex::thread {

class BandedSpd {
 public:
  BandedSpd() = default;
  BandedSpd(int size, int half_bandwidth);

  int size() const { return size_; }
  int half_bandwidth() const { return p_; }

  void SetZero() { band_.setZero(); }
  // A(i, j) for |i - j| <= p (symmetric: either triangle may be given).
  double& At(int i, int j) { return i >= j ? band_(i - j, j) : band_(j - i, i); }
  double At(int i, int j) const { return i >= j ? band_(i - j, j) : band_(j - i, i); }
  // Adds a 3x3 block at block row a, block column b (|a - b| small enough for the band). Only
  // the lower triangle is written, so add each off-diagonal block once with a > b.
  void AddBlock(int a, int b, const Eigen::Matrix3d& block) {
    if (a < b) return;  // upper triangle: not stored
    // Column 3b + c of the lower triangle holds rows 3a + r at offsets 3(a - b) + r - c.
    const int d0 = 3 * (a - b);
    for (int c = 0; c < 3; ++c) {
      double* col = band_.data() + static_cast<std::ptrdiff_t>(3 * b + c) * (p_ + 1);
      for (int r = a == b ? c : 0; r < 3; ++r) col[d0 + r - c] += block(r, c);
    }
  }
  // AddBlock(a, b, s * Identity) without the zeros.
  void AddIdentityBlock(int a, int b, double s) {
    if (a < b) return;
    const int d0 = 3 * (a - b);
    for (int c = 0; c < 3; ++c) band_(d0, 3 * b + c) += s;
  }

  // y = A x using the (unfactorised) band.
  void Multiply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const;

  // In place A = M M^T, twisted at row `twist` (BABE: "burn at both ends"): the rows above it
  // are eliminated downwards (M's top block L, lower triangular), the rows from it down are
  // eliminated upwards on what is left (M's bottom block U, upper triangular). A twist outside
  // [0, size) is size: the plain Cholesky factor. The multi-column solve of columns that touch
  // only rows lo .. hi, with the twist between, then costs O((hi - lo) p) per column instead of
  // O((size - lo) p). Returns false (and leaves garbage) on a non-positive pivot.
  bool Factorize(int twist = -1);
  int twist() const { return twist_; }
  // Solves A x = b in place, after Factorize(). b's rows above first_row must be zero on
  // entry (a sparse right-hand side): the forward substitution starts there.
  void Solve(Eigen::Ref<Eigen::VectorXd> b, int first_row = 0) const;
  // The same for the first `cols` columns of b at once (row-major: each row's columns are
  // contiguous, so the substitutions run across them, vectorised), for sparse columns: column j
  // is nonzero only in rows first_rows[j] .. last_row on entry, first_rows ascending. The
  // solution is computed only in rows first_rows[j] .. SolvedEnd(last_row) of column j (the
  // rest is left unsolved), which b must hold zero down to on entry: above the twist both
  // substitutions of row i run only over the columns that start at or above it; below it they
  // stop at SolvedEnd(last_row).
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  void SolveColumns(RowMajorMatrix& b, int cols, const int* first_rows, int last_row) const;
  int SolvedEnd(int last_row) const {
    return twist_ >= size_ ? size_ - 1 : std::min(size_ - 1, std::max(last_row, twist_ + p_ - 1));
  }

 private:
  int size_ = 0;
  int p_ = 0;
  // band_(d, j) = A(j + d, j), d in [0, p] (LAPACK's lower band storage): column j of the
  // lower triangle is contiguous, so the factorisation's updates are contiguous.
  Eigen::MatrixXd band_;
  // upper_(d, j) = A(j - d, j) for t <= j - d <= j, t the twist: the bottom block after the top
  // part's elimination, then its factor U (column j of U contiguous).
  Eigen::MatrixXd upper_;

  Eigen::VectorXd inv_diag_;  // 1 / M(i, i) after Factorize()
  int twist_ = 0;             // of the last Factorize()
};

// A column of a low-rank term over 3-vector node blocks (the matrix is 3N x 3N, node i owns rows
// 3i..3i+2): u = sum_k weight[k] e_{node[k]} (x) dir. A contact's relative velocity along dir is
// u^T v; a contact impulse p along dir acts on the nodes as u p.
struct NodeColumn {
  int count = 0;  // at most 4 nodes (two links)
  int node[4] = {0, 0, 0, 0};
  double weight[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Vector3d dir = Eigen::Vector3d::Zero();

  double Dot(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  // x += scale * u
  void AddTo(double scale, Eigen::Ref<Eigen::VectorXd> x) const;
};

// Solves with A + U D U^T (A a factorised BandedSpd, U = [u_1 .. u_m] NodeColumns, D = diag(d) > 0)
// by Woodbury's identity, and gives the Delassus operator G = T^T (A + U D U^T)^-1 T of further
// columns T (contact impulses of the same system). One multi-column banded solve Y = A^-1 [U T],
// then small dense algebra: S = D^-1 + U^T A^-1 U (Cholesky), G = T^T Y_T - (U^T Y_T)^T S^-1
// (U^T Y_T). Y is needed only at the rows the columns touch: the columns are solved in the
// order of their first row, each from that row down to the last row any column touches (the
// forward substitution skips its leading zeros, the back substitution stops there; an entry of
// the symmetric U^T Y is read from the column that starts lower; a factor twisted between the
// first and the last row stops both substitutions at the last), and the solution corrections,
// which are Y times a vector, are one banded solve of that vector's sparse right-hand side
// instead.
// Storage sized at construction; nothing allocates afterwards.
class LowRankSolver {
 public:
  LowRankSolver() = default;
  LowRankSolver(int size, int max_columns);
  int max_columns() const { return max_columns_; }

  // columns: the first num_u are U with weights d[0..num_u), the rest are T; they are kept by
  // reference until the next Prepare. Returns false if the small system is not SPD (or a weight
  // is not positive).
  bool Prepare(const BandedSpd& factor, std::span<const NodeColumn> columns, int num_u,
               const double* d);
  // In place: x = A^-1 b on entry, (A + U D U^T)^-1 b on return.
  void CorrectSolution(Eigen::Ref<Eigen::VectorXd> x);
  // G = T^T (A + U D U^T)^-1 T into the leading num_t x num_t block of g.
  void Delassus(Eigen::MatrixXd& g);
  // x += (A + U D U^T)^-1 T p, p of length num_t.
  void AddResponse(const Eigen::Ref<const Eigen::VectorXd>& p, Eigen::Ref<Eigen::VectorXd> x);
  // CorrectSolution and AddResponse with one banded solve: BeginCorrection(x) with x = A^-1 b
  // keeps the correction's coefficients s = S^-1 U^T x; CorrectionDot(t) is column t of T
  // dotted with the correction (x_corrected = x - A^-1 U s, so T_t^T x_corrected =
  // T_t^T x - CorrectionDot(t)); FinishCorrection(p, x) turns x into
  // (A + U D U^T)^-1 b + (A + U D U^T)^-1 T p.
  void BeginCorrection(const Eigen::Ref<const Eigen::VectorXd>& x);
  double CorrectionDot(int t) const;
  void FinishCorrection(const Eigen::Ref<const Eigen::VectorXd>& p, Eigen::Ref<Eigen::VectorXd> x);

 private:
  int size_ = 0;
  int max_columns_ = 0;
  int num_u_ = 0;
  int num_t_ = 0;
  // work_ = A^-1 (sum of the columns first.. first + count - 1 times the coefficients), one
  // banded solve of that sparse vector; false (work_ zero) if the sum touches no row.
  bool SolveColumnSum(const double* coefficients, int first, int count);
  // Row k of x_ut_ (its first num_t_ entries) dotted with p.
  double RowDot(int k, const Eigen::Ref<const Eigen::VectorXd>& p) const;

  const BandedSpd* factor_ = nullptr;    // the caller's, from Prepare
  std::span<const NodeColumn> columns_;  // the caller's, from Prepare
  BandedSpd::RowMajorMatrix y_;          // A^-1 [U T], columns in the order of their first row
  Eigen::VectorXi order_;                // y_'s column s is column order_[s] of [U T]
  Eigen::VectorXi slot_;                 // and column j of [U T] is y_'s column slot_[j]
  Eigen::VectorXi column_first_;         // first touched row of column j of [U T]
  Eigen::VectorXi first_row_;            // first touched row of y_'s columns, ascending
  Eigen::VectorXd work_;                 // length size
  Eigen::MatrixXd h_;  // [U T]^T A^-1 [U T]; lower triangle of S = D^-1 + H_uu factorised
  BandedSpd::RowMajorMatrix x_ut_;  // L_S^-1 H_UT
  Eigen::VectorXd small_;           // length max_columns
  Eigen::VectorXd row_;             // length max_columns: a row of H over y_'s slots
  Eigen::VectorXd correction_;      // S^-1 U^T x of BeginCorrection, length max_columns
};

}  // namespace microdex::thread
