#pragma once
// The immutable tissue model built once from a TissueDef: grid of the finest level, the
// element matrices of every level's template triangles (precomputed once, thesis §3.2), and
// the capacities every per-step buffer is sized to.

#include <cstdint>
#include <vector>

#include "common/fem/element_stiffness.h"
#include "common/fem/tissue_def.h"

namespace microdex::fem {

struct TissueModel {
  TissueDef def;
  int cells_per_side = 0;  // N = 2^max_level
  int nodes_per_side = 0;  // N + 1
  int num_grid_nodes = 0;  // (N + 1)²: node (I, J) has id J·(N + 1) + I
  double h_x_m = 0;        // node spacing of the finest level
  double h_y_m = 0;
  // element_matrices[level][shape] for level 0..max_level (kTemplateTriangles order).
  std::vector<std::array<ElementMatrix, kNumShapes>> element_matrices;
  // Their parts of x- and y-derivatives (CalcElementMatrixParts), for the attached mesh's map.
  std::vector<std::array<ElementMatrix, kNumShapes>> element_matrices_xx;
  std::vector<std::array<ElementMatrix, kNumShapes>> element_matrices_yy;
  // Nested-dissection rank of every grid node (interior nodes 0.., boundary −1): the
  // domain's interior is split at the middle grid line of its longer side, recursively; both
  // halves are ranked before the line. Cuts are dyadic, so they follow quadtree cell sides and
  // the active nodes of a cut separate the multi-scale mesh wherever it is at least that fine.
  std::vector<std::int32_t> nd_rank;  // [num_grid_nodes]
  // Capacities of a step's mesh (leaves, triangles, vertices), proven bounds (README).
  int max_leaves = 0;
  int max_triangles = 0;
  int max_mesh_nodes = 0;

  double NodeX_m(int id) const { return (id % nodes_per_side) * h_x_m; }
  double NodeY_m(int id) const {
    const int row = id / nodes_per_side;
    return row * h_y_m;
  }
  bool IsBoundaryNode(int id) const {
    const int i = id % nodes_per_side, j = id / nodes_per_side;
    return i == 0 || j == 0 || i == cells_per_side || j == cells_per_side;
  }
  // Cell size at `level` (the thesis's element size of that level).
  double CellSizeX_m(int level) const { return def.length_x_m / (1 << level); }
  double CellSizeY_m(int level) const { return def.length_y_m / (1 << level); }
  // Grid-node stride of a level-`level` cell on the finest grid.
  int Stride(int level) const { return 1 << (def.max_level - level); }
};

// Validates the def (std::invalid_argument naming the field) and precomputes the tables.
TissueModel BuildTissueModel(const TissueDef& def);

}  // namespace microdex::fem
