#pragma once
// microdex-bench fem --two-level-probe: iterations of IC(0)-PCG against a two-level
// preconditioner (IC(0) smoothing, Galerkin coarse correction on a uniform bilinear grid) on
// the moving bar's systems. A measurement to decide on a multigrid preconditioner; not a
// solver.

#include <vector>

#include "common/fem/tissue_model.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {

// Steps the tools in order and prints the mean iterations of each method from a zero start.
int RunTwoLevelProbe(const TissueModel& model, const std::vector<ToolContact>& tools);

}  // namespace microdex::fem
