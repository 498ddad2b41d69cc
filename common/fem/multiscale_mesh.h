#pragma once
// The multi-scale mesh of thesis §3.2 (figures 3.1–3.2), chosen afresh each step from the
// nested hierarchy as the tool moves: a quadtree over the levels whose cells are refined
// near the tool, each leaf cut into template triangles (element_stiffness.h). A leaf whose
// neighbour across a side is one level finer is cut as a fan around its centre with that
// side's midpoint as a vertex, so the mesh is conforming: no hanging nodes, no constraints.
// Around the ends of a bar or polyline (where the prescribed displacement stops and the
// solution behaves like r^½) the tree goes on to a finer end level ("end grading",
// TissueDef::end_resolution).

#include <array>
#include <cstdint>
#include <vector>

#include "common/fem/tissue_model.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {

struct Leaf {
  std::int32_t ci = 0;  // cell column and row at its level
  std::int32_t cj = 0;
  std::int8_t level = 0;
  std::uint8_t hanging_mask = 0;  // bit s: side s (bottom, right, top, left) has a midpoint vertex
};

struct Triangle {
  std::array<std::int32_t, 3> node{};  // grid-node ids, counter-clockwise, template order
  std::int8_t level = 0;
  std::int8_t shape = 0;  // index into kTemplateTriangles / TissueModel::element_matrices
};

// The vertices of the tool the mesh is graded towards beyond the nominal level: the pressed
// vertices (z < 0) of a bar or polyline of zero contact radius, multi-scale mesh only.
struct EndZones {
  int num_vertices = 0;
  std::array<double, kMaxToolPoints> x_m{};
  std::array<double, kMaxToolPoints> y_m{};
  int level = 0;   // nominal level of the selection
  int finest = 0;  // the end level, or level when there is no zone
  // Edge grading (TissueDef::edge_resolution): the tool's vertices (planar), and the level
  // below which cells near the tool's parts closer than edge_resolution · h_l to a clamped
  // edge are refined (edge_finest == level: no edge grading).
  int edge_finest = 0;
  int num_tool_points = 0;
  std::array<double, kMaxToolPoints> tool_x_m{};
  std::array<double, kMaxToolPoints> tool_y_m{};
};

// Liang–Barsky: the parameter range [t0, t1] ⊂ [0, 1] of a + t (b − a) inside the box
// [x0, x1] × [y0, y1]; false when the segment misses it.
bool ClipSegmentToBox(double ax, double ay, double bx, double by, double x0, double y0, double x1,
                      double y1, double* t0, double* t1);

// The edge rule: a level-l cell (zones.level ≤ l < zones.edge_finest) is refined when it is
// closer than grading · h_l to a part of the tool within edge_resolution · h_l of an edge.
bool EdgeRefine(const TissueModel& model, const EndZones& zones, int l, int ci, int cj);

// Per-step mesh buffers, sized once to the model's capacities.
struct MeshSelection {
  std::vector<Leaf> leaves;  // [max_leaves], first num_leaves valid, quadtree (Morton) order
  int num_leaves = 0;
  std::vector<Triangle> triangles;  // [max_triangles]
  int num_triangles = 0;
  std::vector<std::int32_t> active_nodes;  // [num_grid_nodes] vertices in first-use order
  int num_active_nodes = 0;
  std::vector<std::uint32_t> node_mark;  // [num_grid_nodes]; == mark: vertex of this mesh
  std::uint32_t mark = 0;
  std::uint64_t signature = 0;  // hash of the leaf set (same leaves ⇒ same mesh)
  int level = 0;                // nominal level: every cell the tool touches is this fine
  EndZones zones;               // end grading of this selection

  bool IsActive(int node) const { return node_mark[node] == mark; }
};

MeshSelection MakeMeshSelection(const TissueModel& model);

// Chooses the leaves (kFine: every cell at `level`; kMultiscale: a level-l cell is refined
// while l < level and its distance to the tool minus the contact radius is below
// grading · h_l, or while l < the end level and its distance to an end-zone vertex is
// below grading · h_l) and cuts them into triangles. Allocation-free. level ≤ def.level.
void SelectMesh(const TissueModel& model, int level, MeshKind kind, const ToolContact& tool,
                MeshSelection& mesh);

// The end zones SelectMesh uses for this tool.
EndZones FindEndZones(const TissueModel& model, int level, MeshKind kind, const ToolContact& tool);

// Level of the leaf containing the point (x, y) of the tool (a point on the tool is always in
// a cell refined down to the nominal level; beyond it only the end rule refines).
int LeafLevelOnTool(const TissueModel& model, const EndZones& zones, double x_m, double y_m);

// The triangles of one leaf (2 for a plain cell, 4–8 for a fan); returns their count.
int LeafTriangles(const TissueModel& model, const Leaf& leaf, std::array<Triangle, 8>& out);

// Grid-node id of template vertex (u, v) (half-cell units) of the level-`level` cell (ci, cj).
inline int CellVertex(const TissueModel& model, int level, int ci, int cj, int u, int v) {
  const int stride = model.Stride(level);
  return (cj * stride + v * stride / 2) * model.nodes_per_side + ci * stride + u * stride / 2;
}

}  // namespace microdex::fem
