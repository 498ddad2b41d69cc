#pragma once
// Conjugate gradient on a symmetric positive definite CSR matrix: the thesis's plain CG and
// preconditioned variants (Jacobi, incomplete Cholesky IC(0), diagonal incomplete Cholesky
// with Eisenstat's trick). Allocation-free after MakeCgWorkspace.

#include <cstdint>
#include <vector>

namespace microdex::fem {

// Full (both triangles) CSR storage with sorted columns; diag[i] is the slot of (i, i).
struct CsrView {
  int n = 0;
  const int* row_ptr = nullptr;
  const int* cols = nullptr;
  const double* vals = nullptr;
  const int* diag = nullptr;
};

// y = A x.
void Multiply(const CsrView& a, const double* x, double* y);

// kDic: the diagonal incomplete Cholesky factor M = (D + L) D⁻¹ (D + Lᵀ), L the strict lower
// triangle of A itself and D chosen so that diag(M) = diag(A). Because M's off-diagonal part is
// A's own, CG runs on the split-preconditioned system with Eisenstat's trick (Eisenstat 1981):
// one product with the preconditioned matrix costs one backward and one forward substitution
// over L, and no product with A.
enum class Preconditioner : std::uint8_t { kNone, kJacobi, kIc0, kDic };

struct CgWorkspace {
  std::vector<double> r, z, p, q;  // [max_n]
  std::vector<double> ic_vals;     // [max_nnz] IC(0) factor L on A's lower pattern
  std::vector<double> inv_diag;    // [max_n] Jacobi: 1 / A_ii; IC(0): 1 / L_ii
  // L's strictly lower entries packed row by row for the substitutions, in single precision:
  // half the bytes streamed per application (the preconditioner need not be exact; it stays
  // a fixed symmetric operator, so PCG is unchanged in kind).
  std::vector<int> l_ptr;     // [max_n + 1]
  std::vector<int> l_cols;    // [max_nnz]
  std::vector<float> l_vals;  // [max_nnz]
  // DIC (kDic): L̃ = D^-1/2 L D^-1/2 packed row by row (double: the scaled system is A itself,
  // so these must be A's entries to the last bit), √d_i, and k_i = 2 − a_ii / d_i.
  std::vector<double> dic_vals;      // [max_nnz]
  std::vector<double> dic_sqrt_d;    // [max_n]
  std::vector<double> dic_k;         // [max_n]
  std::vector<double> u, y;          // [max_n] Eisenstat scratch and the transformed iterate
  std::vector<int> lt_ptr, lt_next;  // [max_n + 1], [max_n] L̃ by columns (CSC)
  std::vector<int> lt_rows;          // [max_nnz]
  std::vector<double> lt_vals;       // [max_nnz]
};
CgWorkspace MakeCgWorkspace(int max_n, int max_nnz);

// IC(0): L Lᵀ ≈ A with L on the pattern of A's lower triangle (rows' entries up to the
// diagonal). Returns false on breakdown (a non-positive pivot).
bool FactorIc0(const CsrView& a, CgWorkspace& ws);
// DIC: the pivots d_i = a_ii − Σ_{j<i} a_ij² / d_j on A's lower pattern (diag M = diag A), then
// D = ω diag(d), ω = `relaxation` (1: plain DIC; any positive D gives an SPD M and the same
// Eisenstat form). Returns false on breakdown (a non-positive d_i; the matrix is SPD but not an
// M-matrix: the tool points' springs add positive off-diagonal entries).
bool FactorDic(const CsrView& a, CgWorkspace& ws, double relaxation = 1.0);
// Jacobi: 1 / diag. Returns false on a non-positive diagonal.
bool FactorJacobi(const CsrView& a, CgWorkspace& ws);

struct CgResult {
  bool converged = false;
  int iterations = 0;
  double relative_residual = 0;  // ‖b − A x‖ / ‖b‖ of the returned x (recurrence value)
};

// Solves A x = b from the initial guess in x; stops at ‖r‖ ≤ tol · ‖b‖. The preconditioner
// must have been factored (FactorIc0 / FactorJacobi) for this A.
CgResult SolveCg(const CsrView& a, const double* b, double* x, Preconditioner preconditioner,
                 double relative_tolerance, int max_iterations, CgWorkspace& ws);

}  // namespace microdex::fem
