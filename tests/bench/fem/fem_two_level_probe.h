#pragma once
// microdex-bench fem --two-level-probe: iterations of IC(0)-PCG against a two-level
// preconditioner (IC(0) smoothing, Galerkin coarse correction on a uniform bilinear grid) on
// the moving bar's systems. A measurement to decide on a multigrid preconditioner; not a
// solver. And --continuity-probe: where the continuity motions' largest force steps are.

#include <vector>

#include "common/fem/tissue_model.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {

// Steps the tools in order and prints the mean iterations of each method from a zero start.
int RunTwoLevelProbe(const TissueModel& model, const std::vector<ToolContact>& tools);

// The continuity motions (level 7, pcg_dic) split into steps on the same mesh and steps where
// the multi-scale mesh changed, for a few tool-point settings; prints the largest changes.
int RunContinuityProbe();

}  // namespace microdex::fem
