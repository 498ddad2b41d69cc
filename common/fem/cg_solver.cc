#include "common/fem/cg_solver.h"

#include <algorithm>
#include <cmath>

namespace microdex::fem {
namespace {

// Four partial sums: a single running sum is a chain of dependent additions (latency-bound,
// ~4 cycles per entry); four independent ones overlap. The summation order is fixed, so the
// result is still deterministic.
double Dot(int n, const double* a, const double* b) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += a[i] * b[i];
    s1 += a[i + 1] * b[i + 1];
    s2 += a[i + 2] * b[i + 2];
    s3 += a[i + 3] * b[i + 3];
  }
  for (; i < n; ++i) s0 += a[i] * b[i];
  return (s0 + s1) + (s2 + s3);
}

// q = A p and returns pᵀ q (one pass over p and q instead of two).
double MultiplyDot(const CsrView& a, const double* p, double* q) {
  double d0 = 0, d1 = 0;
  int i = 0;
  for (; i + 2 <= a.n; i += 2) {
    double s0 = 0, s1 = 0;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) s0 += a.vals[k] * p[a.cols[k]];
    for (int k = a.row_ptr[i + 1]; k < a.row_ptr[i + 2]; ++k) s1 += a.vals[k] * p[a.cols[k]];
    q[i] = s0;
    q[i + 1] = s1;
    d0 += p[i] * s0;
    d1 += p[i + 1] * s1;
  }
  for (; i < a.n; ++i) {
    double s = 0;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) s += a.vals[k] * p[a.cols[k]];
    q[i] = s;
    d0 += p[i] * s;
  }
  return d0 + d1;
}

// x += α p, r −= α q, and returns rᵀ r (one pass).
double UpdateSolution(int n, double alpha, const double* p, const double* q, double* x, double* r) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    for (int j = 0; j < 4; ++j) {
      x[i + j] += alpha * p[i + j];
      r[i + j] -= alpha * q[i + j];
    }
    s0 += r[i] * r[i];
    s1 += r[i + 1] * r[i + 1];
    s2 += r[i + 2] * r[i + 2];
    s3 += r[i + 3] * r[i + 3];
  }
  for (; i < n; ++i) {
    x[i] += alpha * p[i];
    r[i] -= alpha * q[i];
    s0 += r[i] * r[i];
  }
  return (s0 + s1) + (s2 + s3);
}

void ApplyPreconditioner(const CsrView& a, Preconditioner preconditioner, const CgWorkspace& ws,
                         const double* r, double* z) {
  const int n = a.n;
  switch (preconditioner) {
    case Preconditioner::kNone:
      for (int i = 0; i < n; ++i) z[i] = r[i];
      return;
    case Preconditioner::kJacobi:
      for (int i = 0; i < n; ++i) z[i] = ws.inv_diag[i] * r[i];
      return;
    case Preconditioner::kIc0: {
      // Multiplies by 1/L_ii (FactorIc0 keeps them): a division on the substitutions' critical
      // path cost several times a multiplication.
      const int* ptr = ws.l_ptr.data();
      const int* cols = ws.l_cols.data();
      const float* l = ws.l_vals.data();
      const double* inv = ws.inv_diag.data();
      for (int i = 0; i < n; ++i) {  // L y = r
        double s = r[i];
        for (int k = ptr[i]; k < ptr[i + 1]; ++k) s -= static_cast<double>(l[k]) * z[cols[k]];
        z[i] = s * inv[i];
      }
      for (int i = n - 1; i >= 0; --i) {  // Lᵀ z = y, column i of Lᵀ is row i of L
        z[i] *= inv[i];
        const double zi = z[i];
        for (int k = ptr[i]; k < ptr[i + 1]; ++k) z[cols[k]] -= static_cast<double>(l[k]) * zi;
      }
      return;
    }
    case Preconditioner::kDic:
      return;  // SolveCg runs DIC through Eisenstat's trick (SolveCgEisenstat), never here
  }
}

// First v ← r + β v (CG's new direction, in the same pass), then q = Â v with
// Â = (I + L̃)⁻¹ Ã (I + L̃ᵀ)⁻¹, Ã = D^-1/2 A D^-1/2 = (I + L̃) + (I + L̃ᵀ) − diag(k):
// Â v = t + (I + L̃)⁻¹ (v − k∘t), t = (I + L̃ᵀ)⁻¹ v. Returns vᵀ q. t and u are scratch.
double MultiplyEisenstat(int n, const CgWorkspace& ws, const double* r, double beta, double* v,
                         double* t, double* u, double* q) {
  const int* ptr = ws.l_ptr.data();
  const int* cols = ws.l_cols.data();
  const double* l = ws.dic_vals.data();
  const double* k = ws.dic_k.data();
  const int* t_ptr = ws.lt_ptr.data();
  const int* t_rows = ws.lt_rows.data();
  const double* lt = ws.lt_vals.data();
  for (int i = n - 1; i >= 0; --i) {  // row i of L̃ᵀ is column i of L̃
    v[i] = r[i] + beta * v[i];
    double s = v[i];
    for (int e = t_ptr[i]; e < t_ptr[i + 1]; ++e) s -= lt[e] * t[t_rows[e]];
    t[i] = s;
  }
  double d0 = 0, d1 = 0;
  int i = 0;
  for (; i + 2 <= n; i += 2) {
    double s0 = v[i] - k[i] * t[i];
    for (int e = ptr[i]; e < ptr[i + 1]; ++e) s0 -= l[e] * u[cols[e]];
    u[i] = s0;
    q[i] = t[i] + s0;
    d0 += v[i] * q[i];
    double s1 = v[i + 1] - k[i + 1] * t[i + 1];
    for (int e = ptr[i + 1]; e < ptr[i + 2]; ++e) s1 -= l[e] * u[cols[e]];
    u[i + 1] = s1;
    q[i + 1] = t[i + 1] + s1;
    d1 += v[i + 1] * q[i + 1];
  }
  for (; i < n; ++i) {
    double s = v[i] - k[i] * t[i];
    for (int e = ptr[i]; e < ptr[i + 1]; ++e) s -= l[e] * u[cols[e]];
    u[i] = s;
    q[i] = t[i] + s;
    d0 += v[i] * q[i];
  }
  return d0 + d1;
}

// ‖D^1/2 (I + L̃) r̂‖: the residual b − A x of the original system from the transformed one's.
double OriginalResidualNorm(int n, const CgWorkspace& ws, const double* r_hat) {
  const int* ptr = ws.l_ptr.data();
  const int* cols = ws.l_cols.data();
  const double* l = ws.dic_vals.data();
  const double* sqrt_d = ws.dic_sqrt_d.data();
  double s0 = 0, s1 = 0;
  for (int i = 0; i < n; ++i) {
    double s = r_hat[i];
    for (int e = ptr[i]; e < ptr[i + 1]; ++e) s += l[e] * r_hat[cols[e]];
    s *= sqrt_d[i];
    ((i & 1) != 0 ? s1 : s0) += s * s;
  }
  return std::sqrt(s0 + s1);
}

// CG on Â ŷ = b̂, b̂ = (I + L̃)⁻¹ D^-1/2 b, x = D^-1/2 (I + L̃ᵀ)⁻¹ ŷ: PCG with M = (D + L) D⁻¹
// (D + Lᵀ) in exact arithmetic, at the cost of two substitutions per iteration. It stops on
// the original residual ‖b − A x‖ ≤ tol ‖b‖, as the other variants do: the transformed one,
// r̂ = (I + L̃)⁻¹ D^-1/2 r, is the cheap test, and the original norm is computed (one pass)
// whenever r̂ has come within kCheckMargin of the threshold that corresponds to the target at
// the ratio of the two norms last seen (the ratio drifts as CG goes on: stopping on the
// threshold alone ran 2–3 iterations more than needed on the moving bar).
constexpr double kCheckMargin = 3;

CgResult SolveCgEisenstat(const CsrView& a, const double* b, double* x, double relative_tolerance,
                          int max_iterations, CgWorkspace& ws) {
  const int n = a.n;
  CgResult result;
  double* r = ws.r.data();
  double* t = ws.z.data();
  double* p = ws.p.data();
  double* q = ws.q.data();
  double* u = ws.u.data();
  double* y = ws.y.data();
  const int* ptr = ws.l_ptr.data();
  const int* cols = ws.l_cols.data();
  const double* l = ws.dic_vals.data();
  const double* sqrt_d = ws.dic_sqrt_d.data();
  const double* inv_sqrt_d = ws.inv_diag.data();
  const double b_norm = std::sqrt(Dot(n, b, b));
  if (b_norm == 0) {
    for (int i = 0; i < n; ++i) x[i] = 0;
    result.converged = true;
    return result;
  }
  const double target = relative_tolerance * b_norm;
  Multiply(a, x, q);
  for (int i = 0; i < n; ++i) r[i] = b[i] - q[i];
  double r_norm = std::sqrt(Dot(n, r, r));
  if (r_norm <= target) {
    result.relative_residual = r_norm / b_norm;
    result.converged = std::isfinite(r_norm);
    return result;
  }
  // r̂ = (I + L̃)⁻¹ D^-1/2 r in place; ŷ = (I + L̃ᵀ) D^1/2 x.
  for (int i = 0; i < n; ++i) {
    double s = r[i] * inv_sqrt_d[i];
    for (int e = ptr[i]; e < ptr[i + 1]; ++e) s -= l[e] * r[cols[e]];
    r[i] = s;
  }
  for (int i = 0; i < n; ++i) y[i] = sqrt_d[i] * x[i];
  for (int i = n - 1; i >= 0; --i) {
    const double wi = sqrt_d[i] * x[i];
    for (int e = ptr[i]; e < ptr[i + 1]; ++e) y[cols[e]] += l[e] * wi;
  }
  double rho = Dot(n, r, r);
  double target_hat = target * std::sqrt(rho) / r_norm;
  double beta = 0;  // the first direction is r̂ itself
  for (int i = 0; i < n; ++i) p[i] = 0;
  while (result.iterations < max_iterations) {
    const double pq = MultiplyEisenstat(n, ws, r, beta, p, t, u, q);
    if (!(pq > 0)) break;  // breakdown: not positive definite or NaN
    const double alpha = rho / pq;
    const double rho_next = UpdateSolution(n, alpha, p, q, y, r);
    ++result.iterations;
    if (!std::isfinite(rho_next)) break;
    const double r_hat_norm = std::sqrt(rho_next);
    if (r_hat_norm <= kCheckMargin * target_hat) {
      r_norm = OriginalResidualNorm(n, ws, r);
      if (r_norm <= target) break;
      target_hat = target * r_hat_norm / r_norm;
    }
    beta = rho_next / rho;
    rho = rho_next;
  }
  if (!(r_norm <= target)) r_norm = OriginalResidualNorm(n, ws, r);
  // x = D^-1/2 (I + L̃ᵀ)⁻¹ ŷ.
  for (int i = n - 1; i >= 0; --i) {
    const double yi = y[i];
    for (int e = ptr[i]; e < ptr[i + 1]; ++e) y[cols[e]] -= l[e] * yi;
    x[i] = yi * inv_sqrt_d[i];
  }
  result.relative_residual = r_norm / b_norm;
  result.converged = r_norm <= target && std::isfinite(r_norm);
  return result;
}

}  // namespace

void Multiply(const CsrView& a, const double* x, double* y) {
  for (int i = 0; i < a.n; ++i) {
    double s = 0;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) s += a.vals[k] * x[a.cols[k]];
    y[i] = s;
  }
}

CgWorkspace MakeCgWorkspace(int max_n, int max_nnz) {
  CgWorkspace ws;
  ws.r.resize(max_n);
  ws.z.resize(max_n);
  ws.p.resize(max_n);
  ws.q.resize(max_n);
  ws.inv_diag.resize(max_n);
  ws.ic_vals.resize(max_nnz);
  ws.l_ptr.resize(max_n + 1);
  ws.l_cols.resize(max_nnz);
  ws.l_vals.resize(max_nnz);
  ws.dic_vals.resize(max_nnz);
  ws.dic_sqrt_d.resize(max_n);
  ws.dic_k.resize(max_n);
  ws.u.resize(max_n);
  ws.y.resize(max_n);
  ws.lt_ptr.resize(max_n + 1);
  ws.lt_next.resize(max_n);
  ws.lt_rows.resize(max_nnz);
  ws.lt_vals.resize(max_nnz);
  return ws;
}

bool FactorJacobi(const CsrView& a, CgWorkspace& ws) {
  for (int i = 0; i < a.n; ++i) {
    const double d = a.vals[a.diag[i]];
    if (!(d > 0) || !std::isfinite(d)) return false;
    ws.inv_diag[i] = 1.0 / d;
  }
  return true;
}

bool FactorIc0(const CsrView& a, CgWorkspace& ws) {
  double* l = ws.ic_vals.data();
  for (int i = 0; i < a.n; ++i) {
    const int row_begin = a.row_ptr[i];
    for (int k = row_begin; k < a.diag[i]; ++k) {
      // L_ij = (A_ij − Σ_{m<j} L_im L_jm) / L_jj over the common pattern of rows i and j.
      const int j = a.cols[k];
      double s = a.vals[k];
      int p = row_begin, q = a.row_ptr[j];
      while (p < k && q < a.diag[j]) {
        if (a.cols[p] == a.cols[q]) {
          s -= l[p++] * l[q++];
        } else if (a.cols[p] < a.cols[q]) {
          ++p;
        } else {
          ++q;
        }
      }
      l[k] = s / l[a.diag[j]];
    }
    double d = a.vals[a.diag[i]];
    for (int k = row_begin; k < a.diag[i]; ++k) d -= l[k] * l[k];
    if (!(d > 0) || !std::isfinite(d)) return false;
    l[a.diag[i]] = std::sqrt(d);
    ws.inv_diag[i] = 1.0 / l[a.diag[i]];
  }
  int packed = 0;
  for (int i = 0; i < a.n; ++i) {
    ws.l_ptr[i] = packed;
    for (int k = a.row_ptr[i]; k < a.diag[i]; ++k) {
      ws.l_cols[packed] = a.cols[k];
      ws.l_vals[packed++] = static_cast<float>(l[k]);
    }
  }
  ws.l_ptr[a.n] = packed;
  return true;
}

bool FactorDic(const CsrView& a, CgWorkspace& ws, double relaxation) {
  // inv_diag holds 1/√d (the scaling); d_j itself is √d_j².
  for (int i = 0; i < a.n; ++i) {
    const double a_ii = a.vals[a.diag[i]];
    double d = a_ii;
    for (int k = a.row_ptr[i]; k < a.diag[i]; ++k) {
      const double inv_sqrt_dj = ws.inv_diag[a.cols[k]];
      const double scaled = a.vals[k] * inv_sqrt_dj;
      d -= scaled * scaled;
    }
    if (!(d > 0) || !std::isfinite(d)) return false;
    ws.dic_sqrt_d[i] = std::sqrt(d);
    ws.inv_diag[i] = 1.0 / ws.dic_sqrt_d[i];
  }
  // The pivots of plain DIC, then scaled (an SPD M for any positive D).
  const double sqrt_relaxation = std::sqrt(relaxation);
  for (int i = 0; i < a.n; ++i) {
    ws.dic_sqrt_d[i] *= sqrt_relaxation;
    ws.inv_diag[i] = 1.0 / ws.dic_sqrt_d[i];
    ws.dic_k[i] = 2.0 - a.vals[a.diag[i]] * ws.inv_diag[i] * ws.inv_diag[i];
  }
  int packed = 0;
  for (int i = 0; i < a.n; ++i) {
    ws.l_ptr[i] = packed;
    const double inv_sqrt_di = ws.inv_diag[i];
    for (int k = a.row_ptr[i]; k < a.diag[i]; ++k) {
      ws.l_cols[packed] = a.cols[k];
      ws.dic_vals[packed++] = a.vals[k] * inv_sqrt_di * ws.inv_diag[a.cols[k]];
    }
  }
  ws.l_ptr[a.n] = packed;
  // L̃ by columns, for the backward substitution by rows of L̃ᵀ (a gather, like the forward one).
  int* t_ptr = ws.lt_ptr.data();
  std::fill_n(t_ptr, a.n + 1, 0);
  for (int e = 0; e < packed; ++e) ++t_ptr[ws.l_cols[e] + 1];
  for (int j = 0; j < a.n; ++j) t_ptr[j + 1] += t_ptr[j];
  int* next = ws.lt_next.data();
  std::copy_n(t_ptr, a.n, next);
  for (int i = 0; i < a.n; ++i) {
    for (int e = ws.l_ptr[i]; e < ws.l_ptr[i + 1]; ++e) {
      const int slot = next[ws.l_cols[e]]++;
      ws.lt_rows[slot] = i;
      ws.lt_vals[slot] = ws.dic_vals[e];
    }
  }
  return true;
}

CgResult SolveCg(const CsrView& a, const double* b, double* x, Preconditioner preconditioner,
                 double relative_tolerance, int max_iterations, CgWorkspace& ws) {
  if (preconditioner == Preconditioner::kDic)
    return SolveCgEisenstat(a, b, x, relative_tolerance, max_iterations, ws);
  const int n = a.n;
  CgResult result;
  double* r = ws.r.data();
  double* z = ws.z.data();
  double* p = ws.p.data();
  double* q = ws.q.data();
  const double b_norm = std::sqrt(Dot(n, b, b));
  if (b_norm == 0) {
    for (int i = 0; i < n; ++i) x[i] = 0;
    result.converged = true;
    return result;
  }
  Multiply(a, x, q);
  for (int i = 0; i < n; ++i) r[i] = b[i] - q[i];
  double r_norm = std::sqrt(Dot(n, r, r));
  const double target = relative_tolerance * b_norm;
  ApplyPreconditioner(a, preconditioner, ws, r, z);
  for (int i = 0; i < n; ++i) p[i] = z[i];
  double rz = Dot(n, r, z);
  while (r_norm > target && result.iterations < max_iterations) {
    const double pq = MultiplyDot(a, p, q);
    if (!(pq > 0)) break;  // breakdown: not positive definite or NaN
    const double alpha = rz / pq;
    r_norm = std::sqrt(UpdateSolution(n, alpha, p, q, x, r));
    ++result.iterations;
    if (r_norm <= target) break;
    ApplyPreconditioner(a, preconditioner, ws, r, z);
    const double rz_next = Dot(n, r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (int i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
  }
  result.relative_residual = r_norm / b_norm;
  result.converged = r_norm <= target && std::isfinite(r_norm);
  return result;
}

}  // namespace microdex::fem
