#pragma once
// Sparse direct solve with CHOLMOD (SuiteSparse 5): the symbolic analysis is done once per
// sparsity pattern and kept in a slot, the numeric factorisation reuses it, and the solve
// reuses its dense workspace (cholmod_solve2). The fill-reducing ordering is either CHOLMOD's
// AMD (with postordering) or the caller's own numbering (natural order, no postordering: the
// analysis is then only the elimination tree and column counts, and the factorisation reads
// the upper triangle in place without a permuted copy). CHOLMOD allocates through its own
// malloc hooks: on a new pattern (analysis) and when the system size changes; never for a
// repeated pattern (measured by the allocation test).

#include <vector>

#include "common/fem/cg_solver.h"

struct cholmod_common_struct;
struct cholmod_factor_struct;
struct cholmod_dense_struct;

namespace microdex::fem {

class CholmodSolver {
 public:
  CholmodSolver(int num_slots, bool natural_ordering);
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  // Symbolic analysis of `a`'s pattern into `slot` (replacing what was there).
  bool Analyze(int slot, const CsrView& a);
  // Numeric factorisation of `a` with the slot's analysis. False if not positive definite.
  bool Factorize(int slot, const CsrView& a);
  // x = A⁻¹ b with the slot's factor.
  bool Solve(int slot, const double* b, double* x, int n);
  bool HasAnalysis(int slot) const { return factors_[slot] != nullptr; }

 private:
  cholmod_common_struct* common_;
  std::vector<cholmod_factor_struct*> factors_;
  cholmod_dense_struct* x_ = nullptr;
  cholmod_dense_struct* y_ = nullptr;
  cholmod_dense_struct* e_ = nullptr;
};

}  // namespace microdex::fem
