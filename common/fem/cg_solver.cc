#include "common/fem/cg_solver.h"

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
  }
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

CgResult SolveCg(const CsrView& a, const double* b, double* x, Preconditioner preconditioner,
                 double relative_tolerance, int max_iterations, CgWorkspace& ws) {
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
