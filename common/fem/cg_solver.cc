#include "common/fem/cg_solver.h"

#include <cmath>

namespace microdex::fem {
namespace {

double Dot(int n, const double* a, const double* b) {
  double s = 0;
  for (int i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
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
    Multiply(a, p, q);
    const double pq = Dot(n, p, q);
    if (!(pq > 0)) break;  // breakdown: not positive definite or NaN
    const double alpha = rz / pq;
    for (int i = 0; i < n; ++i) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
    }
    r_norm = std::sqrt(Dot(n, r, r));
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
