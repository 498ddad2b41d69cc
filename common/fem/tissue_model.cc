#include "common/fem/tissue_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "common/base/check.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {
namespace {

// Ranks the grid nodes of [i0, i1) × [j0, j1) (interior node indices) in nested-dissection
// order: the halves first, the separating grid line last.
void RankNestedDissection(int i0, int i1, int j0, int j1, int side, std::int32_t& next,
                          std::vector<std::int32_t>& rank) {
  const int w = i1 - i0, h = j1 - j0;
  if (w <= 0 || h <= 0) return;
  if (w * h <= 4) {
    for (int j = j0; j < j1; ++j)
      for (int i = i0; i < i1; ++i) rank[static_cast<size_t>(j) * side + i] = next++;
    return;
  }
  if (w >= h) {
    const int m = (i0 + i1) / 2;
    RankNestedDissection(i0, m, j0, j1, side, next, rank);
    RankNestedDissection(m + 1, i1, j0, j1, side, next, rank);
    for (int j = j0; j < j1; ++j) rank[static_cast<size_t>(j) * side + m] = next++;
  } else {
    const int m = (j0 + j1) / 2;
    RankNestedDissection(i0, i1, j0, m, side, next, rank);
    RankNestedDissection(i0, i1, m + 1, j1, side, next, rank);
    for (int i = i0; i < i1; ++i) rank[static_cast<size_t>(m) * side + i] = next++;
  }
}

}  // namespace

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
  model.element_matrices_xx.resize(def.max_level + 1);
  model.element_matrices_yy.resize(def.max_level + 1);
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
      const bool parts_ok = CalcElementMatrixParts(x_m, y_m, def.shear_modulus_Pa, def.thickness_m,
                                                   model.element_matrices_xx[level][shape],
                                                   model.element_matrices_yy[level][shape]);
      MICRODEX_CHECK(parts_ok);
    }
  }
  model.nd_rank.assign(model.num_grid_nodes, -1);
  std::int32_t next = 0;
  RankNestedDissection(1, model.cells_per_side, 1, model.cells_per_side, model.nodes_per_side, next,
                       model.nd_rank);

  // Leaves at levels ≤ level: each covers at least one level-`level` cell, so at most 4^level.
  // A finest such leaf without finer neighbours gives 2 triangles and a coarser (fan) leaf at
  // most 8 while covering 4 cells: a + 4b ≤ 4^level bounds 2a + 8b by 2·4^level. Their
  // vertices are nodes of the level grid.
  const std::int64_t cells = std::int64_t{1} << (2 * def.level);
  const std::int64_t level_nodes = ((std::int64_t{1} << def.level) + 1) * ((1 << def.level) + 1);
  // End zones (multi-scale, vertices of a tool with zero contact radius): the children of a
  // level-(level + j) cell refined by the end rule, box distance to the vertex below
  // grading·max(hx, hy). Such cells fit in a square of side 2·grading·aspect + 2 cells around
  // the vertex, 4 children each, for j < min(end_levels, max_level − level), at most
  // kMaxToolPoints vertices.
  std::int64_t extra = 0;
  const int end_levels = std::min(def.end_levels, def.max_level - def.level);
  if (def.mesh == MeshKind::kMultiscale && def.end_resolution > 0 && end_levels > 0) {
    const double aspect =
        std::max(def.length_x_m, def.length_y_m) / std::min(def.length_x_m, def.length_y_m);
    const std::int64_t span = 2 * static_cast<std::int64_t>(std::ceil(def.grading * aspect)) + 2;
    extra = std::int64_t{kMaxToolPoints} * end_levels * 4 * span * span;
  }
  // Edge grading: FindEndZones refines a level only while its bound on the leaves the edge rule
  // adds stays within edge_max_leaves.
  // Each refined cell makes 4 leaves and at most 5 new nodes (side midpoints, centre); a leaf
  // cut as a fan adds its centre, and so may each of the ≤ 4 neighbours of a refined cell:
  // ≤ 5/4 + 1 + 1 < 4 nodes per counted leaf; ≤ 8 triangles per leaf and 6 more per fan
  // neighbour: 14.
  std::int64_t edge = 0;
  if (def.mesh == MeshKind::kMultiscale && def.edge_resolution > 0 &&
      std::min(def.edge_levels, def.max_level - def.level) > 0)
    edge = def.edge_max_leaves;
  // A zone leaf gives at most 8 triangles; a level-`level` leaf next to a zone becomes a fan
  // (up to 6 more triangles and a centre node), and there are fewer such leaves than zone
  // leaves. A zone leaf adds at most its 4 corners and its centre.
  const std::int64_t all_cells = std::int64_t{model.cells_per_side} * model.cells_per_side;
  model.max_leaves = static_cast<int>(std::min(all_cells, cells + extra + edge));
  model.max_triangles =
      static_cast<int>(std::min(2 * all_cells, 2 * cells + 14 * extra + 14 * edge));
  model.max_mesh_nodes = static_cast<int>(
      std::min<std::int64_t>(model.num_grid_nodes, level_nodes + 6 * extra + 4 * edge));
  return model;
}

}  // namespace microdex::fem
