#include "common/fem/cholmod_solver.h"

#include <cholmod.h>

#include <cmath>
#include <cstring>

namespace microdex::fem {
namespace {

// A header over our CSR arrays: a symmetric matrix stored in full is its own CSC, and
// stype = 1 makes CHOLMOD read only the upper triangle, so nothing is copied.
cholmod_sparse WrapSparse(const CsrView& a) {
  cholmod_sparse s;
  std::memset(&s, 0, sizeof(s));
  s.nrow = static_cast<size_t>(a.n);
  s.ncol = static_cast<size_t>(a.n);
  s.nzmax = static_cast<size_t>(a.row_ptr[a.n]);
  s.p = const_cast<int*>(a.row_ptr);
  s.i = const_cast<int*>(a.cols);
  s.x = const_cast<double*>(a.vals);
  s.stype = 1;
  s.itype = CHOLMOD_INT;
  s.xtype = CHOLMOD_REAL;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = 1;
  s.packed = 1;
  return s;
}

}  // namespace

CholmodSolver::CholmodSolver(int num_slots, bool natural_ordering)
    : common_(new cholmod_common), factors_(num_slots, nullptr) {
  cholmod_start(common_);
  common_->print = 0;  // status is checked by the caller; nothing printed in the loop
  common_->nmethods = 1;
  common_->method[0].ordering = natural_ordering ? CHOLMOD_NATURAL : CHOLMOD_AMD;
  common_->postorder = natural_ordering ? 0 : 1;
  // Simplicial for the multi-scale systems (few flops per entry of L), supernodal for the
  // large fine meshes: CHOLMOD's own choice.
  common_->supernodal = CHOLMOD_AUTO;
}

CholmodSolver::~CholmodSolver() {
  for (cholmod_factor*& f : factors_) {
    if (f != nullptr) cholmod_free_factor(&f, common_);
  }
  if (x_ != nullptr) cholmod_free_dense(&x_, common_);
  if (y_ != nullptr) cholmod_free_dense(&y_, common_);
  if (e_ != nullptr) cholmod_free_dense(&e_, common_);
  cholmod_finish(common_);
  delete common_;
}

bool CholmodSolver::Analyze(int slot, const CsrView& a) {
  if (factors_[slot] != nullptr) cholmod_free_factor(&factors_[slot], common_);
  cholmod_sparse s = WrapSparse(a);
  factors_[slot] = cholmod_analyze(&s, common_);
  return factors_[slot] != nullptr && common_->status == CHOLMOD_OK;
}

bool CholmodSolver::Factorize(int slot, const CsrView& a) {
  if (factors_[slot] == nullptr) return false;
  cholmod_sparse s = WrapSparse(a);
  const int ok = cholmod_factorize(&s, factors_[slot], common_);
  return ok != 0 && common_->status == CHOLMOD_OK &&
         factors_[slot]->minor == static_cast<size_t>(a.n);
}

bool CholmodSolver::Solve(int slot, const double* b, double* x, int n) {
  if (factors_[slot] == nullptr) return false;
  cholmod_dense bd;
  std::memset(&bd, 0, sizeof(bd));
  bd.nrow = static_cast<size_t>(n);
  bd.ncol = 1;
  bd.nzmax = static_cast<size_t>(n);
  bd.d = static_cast<size_t>(n);
  bd.x = const_cast<double*>(b);
  bd.xtype = CHOLMOD_REAL;
  bd.dtype = CHOLMOD_DOUBLE;
  const int ok =
      cholmod_solve2(CHOLMOD_A, factors_[slot], &bd, nullptr, &x_, nullptr, &y_, &e_, common_);
  if (ok == 0 || x_ == nullptr) return false;
  const double* xs = static_cast<const double*>(x_->x);
  for (int i = 0; i < n; ++i) x[i] = xs[i];
  return true;
}

}  // namespace microdex::fem
