#include "common/fem/tissue_model.h"

#include "common/base/check.h"

namespace microdex::fem {

TissueModel BuildTissueModel(const TissueDef& def) {
  def.Validate();
  TissueModel model;
  model.def = def;
  model.cells_per_side = 1 << def.max_level;
  model.nodes_per_side = model.cells_per_side + 1;
  model.num_grid_nodes = model.nodes_per_side * model.nodes_per_side;
  model.h_x_m = def.length_x_m / model.cells_per_side;
  model.h_y_m = def.length_y_m / model.cells_per_side;
  model.element_matrices.resize(def.max_level + 1);
  for (int level = 0; level <= def.max_level; ++level) {
    const double half_x_m = 0.5 * model.CellSizeX_m(level);
    const double half_y_m = 0.5 * model.CellSizeY_m(level);
    for (int shape = 0; shape < kNumShapes; ++shape) {
      std::array<double, 3> x_m{}, y_m{};
      for (int k = 0; k < 3; ++k) {
        x_m[k] = kTemplateTriangles[shape][k].u * half_x_m;
        y_m[k] = kTemplateTriangles[shape][k].v * half_y_m;
      }
      const bool ok = CalcElementMatrix(x_m, y_m, def.shear_modulus_Pa, def.thickness_m,
                                        model.element_matrices[level][shape]);
      MICRODEX_CHECK(ok);
    }
  }
  model.max_leaves = model.cells_per_side * model.cells_per_side;
  // A finest-level leaf gives 2 triangles and covers 4^−L of the domain; a coarser (fan) leaf
  // gives at most 8 and covers at least 4·4^−L, so a + 4b ≤ 4^L bounds 2a + 8b by 2·4^L.
  model.max_triangles = 2 * model.max_leaves;
  return model;
}

}  // namespace microdex::fem
