#include "common/fem/multiscale_mesh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/base/check.h"

namespace microdex::fem {
namespace {

constexpr std::uint64_t kFnvOffset = 1469598103934665603ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

std::uint64_t HashMix(std::uint64_t h, std::uint64_t value) {
  for (int b = 0; b < 8; ++b) {
    h ^= (value >> (8 * b)) & 0xffu;
    h *= kFnvPrime;
  }
  return h;
}

// Side s runs from corner s to corner s+1 (BL, BR, TR, TL); its midpoint in half-cell units.
constexpr std::array<TemplateVertex, 4> kCorners = {{{0, 0}, {2, 0}, {2, 2}, {0, 2}}};
constexpr std::array<TemplateVertex, 4> kMidpoints = {{{1, 0}, {2, 1}, {1, 2}, {0, 1}}};

void MarkNode(MeshSelection& mesh, int node) {
  if (mesh.node_mark[node] != mesh.mark) {
    MICRODEX_CHECK(mesh.num_active_nodes < static_cast<int>(mesh.active_nodes.size()));
    mesh.node_mark[node] = mesh.mark;
    mesh.active_nodes[mesh.num_active_nodes++] = node;
  }
}

// The end rule: a level-l cell (level ≤ l < finest) is refined when a zone vertex is closer
// than grading · max(hx, hy) to it.
bool EndRefine(const TissueModel& model, const EndZones& zones, int l, int ci, int cj) {
  if (l >= zones.finest) return false;
  const double hx = model.CellSizeX_m(l), hy = model.CellSizeY_m(l);
  const double x0 = ci * hx, y0 = cj * hy, x1 = x0 + hx, y1 = y0 + hy;
  const double reach = model.def.grading * std::max(hx, hy);
  for (int k = 0; k < zones.num_vertices; ++k) {
    const double dx = std::max({x0 - zones.x_m[k], 0.0, zones.x_m[k] - x1});
    const double dy = std::max({y0 - zones.y_m[k], 0.0, zones.y_m[k] - y1});
    if (dx * dx + dy * dy < reach * reach) return true;
  }
  return false;
}

double PointBoxDistance2(double px, double py, double x0, double y0, double x1, double y1) {
  const double dx = std::max({x0 - px, 0.0, px - x1});
  const double dy = std::max({y0 - py, 0.0, py - y1});
  return dx * dx + dy * dy;
}

double PointSegmentDistance2(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0) : 0.0;
  const double ex = ax + t * dx - px, ey = ay + t * dy - py;
  return ex * ex + ey * ey;
}

// Squared distance between the segment a–b and the box [x0, x1] × [y0, y1]: 0 when they meet,
// else reached at a vertex of one of them.
double SegmentBoxDistance2(double ax, double ay, double bx, double by, double x0, double y0,
                           double x1, double y1) {
  double t0 = 0, t1 = 0;
  if (ClipSegmentToBox(ax, ay, bx, by, x0, y0, x1, y1, &t0, &t1)) return 0;
  double best = std::min(PointBoxDistance2(ax, ay, x0, y0, x1, y1),
                         PointBoxDistance2(bx, by, x0, y0, x1, y1));
  const double cx[4] = {x0, x1, x1, x0};
  const double cy[4] = {y0, y0, y1, y1};
  for (int c = 0; c < 4; ++c)
    best = std::min(best, PointSegmentDistance2(cx[c], cy[c], ax, ay, bx, by));
  return best;
}

// Calls f(ax, ay, bx, by) for each part of the tool (clipped to the domain) closer than
// `margin_m` to an edge: a segment minus the box inset by the margin, up to two parts.
template <typename F>
void ForEachEdgePart(const TissueModel& model, const EndZones& zones, double margin_m, F&& f) {
  const double lx = model.def.length_x_m, ly = model.def.length_y_m;
  for (int k = 0; k + 1 < zones.num_tool_points; ++k) {
    const double ax = zones.tool_x_m[k], ay = zones.tool_y_m[k];
    const double bx = zones.tool_x_m[k + 1], by = zones.tool_y_m[k + 1];
    double ta = 0, tb = 0;
    if (!ClipSegmentToBox(ax, ay, bx, by, 0, 0, lx, ly, &ta, &tb)) continue;
    const double dx = bx - ax, dy = by - ay;
    double u0 = 0, u1 = 0;
    const bool inner =
        2 * margin_m < std::min(lx, ly) && ClipSegmentToBox(ax, ay, bx, by, margin_m, margin_m,
                                                            lx - margin_m, ly - margin_m, &u0, &u1);
    if (!inner) {
      f(ax + ta * dx, ay + ta * dy, ax + tb * dx, ay + tb * dy);
      continue;
    }
    if (u0 > ta) f(ax + ta * dx, ay + ta * dy, ax + u0 * dx, ay + u0 * dy);
    if (tb > u1) f(ax + u1 * dx, ay + u1 * dy, ax + tb * dx, ay + tb * dy);
  }
}

double EdgeMargin_m(const TissueModel& model, int l) {
  return model.def.edge_resolution * std::max(model.CellSizeX_m(l), model.CellSizeY_m(l));
}

struct Selector {
  const TissueModel& model;
  int level;
  MeshKind kind;
  const ToolContact& tool;
  MeshSelection& mesh;

  bool Refine(int l, int ci, int cj) const {
    if (l >= level)
      return EndRefine(model, mesh.zones, l, ci, cj) || EdgeRefine(model, mesh.zones, l, ci, cj);
    if (kind == MeshKind::kFine) return true;
    const double hx = model.CellSizeX_m(l), hy = model.CellSizeY_m(l);
    const double d = ToolBoxDistance_m(tool, ci * hx, cj * hy, (ci + 1) * hx, (cj + 1) * hy);
    return d - tool.contact_radius_m < model.def.grading * std::max(hx, hy);
  }

  void Visit(int l, int ci, int cj) {
    if (Refine(l, ci, cj)) {
      for (int k = 0; k < 4; ++k) Visit(l + 1, 2 * ci + (k & 1), 2 * cj + (k >> 1));
      return;
    }
    MICRODEX_CHECK(mesh.num_leaves < static_cast<int>(mesh.leaves.size()));
    Leaf& leaf = mesh.leaves[mesh.num_leaves++];
    leaf.ci = ci;
    leaf.cj = cj;
    leaf.level = static_cast<std::int8_t>(l);
    leaf.hanging_mask = 0;
    for (const TemplateVertex& c : kCorners) MarkNode(mesh, CellVertex(model, l, ci, cj, c.u, c.v));
    mesh.signature = HashMix(mesh.signature, (static_cast<std::uint64_t>(l) << 56) ^
                                                 (static_cast<std::uint64_t>(ci) << 28) ^
                                                 static_cast<std::uint64_t>(cj));
  }
};

}  // namespace

MeshSelection MakeMeshSelection(const TissueModel& model) {
  MeshSelection mesh;
  mesh.leaves.resize(model.max_leaves);
  mesh.triangles.resize(model.max_triangles);
  mesh.active_nodes.resize(model.max_mesh_nodes);
  mesh.node_mark.assign(model.num_grid_nodes, 0);
  return mesh;
}

int LeafTriangles(const TissueModel& model, const Leaf& leaf, std::array<Triangle, 8>& out) {
  int count = 0;
  auto emit = [&](int shape) {
    Triangle& t = out[count++];
    t.level = leaf.level;
    t.shape = static_cast<std::int8_t>(shape);
    for (int k = 0; k < 3; ++k) {
      const TemplateVertex& v = kTemplateTriangles[shape][k];
      t.node[k] = CellVertex(model, leaf.level, leaf.ci, leaf.cj, v.u, v.v);
    }
  };
  if (leaf.hanging_mask == 0) {
    emit(kShapeLower);
    emit(kShapeUpper);
    return count;
  }
  for (int side = 0; side < 4; ++side) {
    if (leaf.hanging_mask & (1u << side)) {
      emit(kShapeFanHalf + 2 * side);
      emit(kShapeFanHalf + 2 * side + 1);
    } else {
      emit(kShapeFanFull + side);
    }
  }
  return count;
}

EndZones FindEndZones(const TissueModel& model, int level, MeshKind kind, const ToolContact& tool) {
  EndZones zones;
  zones.level = level;
  zones.finest = level;
  zones.edge_finest = level;
  const TissueDef& def = model.def;
  if (kind != MeshKind::kMultiscale || tool.num_points < 2 || tool.contact_radius_m > 0)
    return zones;
  if (def.end_resolution > 0) {
    double length_m = 0;
    for (int k = 0; k + 1 < tool.num_points; ++k)
      length_m += std::hypot(tool.p_SP[k + 1].x() - tool.p_SP[k].x(),
                             tool.p_SP[k + 1].y() - tool.p_SP[k].y());
    // A cell size equal to the target up to rounding counts as reaching it.
    constexpr double kRelTol = 1e-9;
    const double cell_m = length_m / def.end_resolution * (1 + kRelTol);
    int end_level = level;
    const int last = std::min(def.max_level, level + def.end_levels);
    while (end_level < last &&
           std::max(model.CellSizeX_m(end_level), model.CellSizeY_m(end_level)) > cell_m)
      ++end_level;
    if (end_level > level) {
      for (int k = 0; k < tool.num_points; ++k) {
        if (!(tool.p_SP[k].z() < 0)) continue;  // not pressed: the contact does not end here
        zones.x_m[zones.num_vertices] = tool.p_SP[k].x();
        zones.y_m[zones.num_vertices] = tool.p_SP[k].y();
        ++zones.num_vertices;
      }
      if (zones.num_vertices > 0) zones.finest = end_level;
    }
  }
  MICRODEX_CHECK(zones.finest <= def.max_level);
  if (def.edge_resolution > 0 && def.tool_constraint == ToolConstraint::kPenaltyPoints) {
    zones.num_tool_points = tool.num_points;
    for (int k = 0; k < tool.num_points; ++k) {
      zones.tool_x_m[k] = tool.p_SP[k].x();
      zones.tool_y_m[k] = tool.p_SP[k].y();
    }
    // Each level's refinement is bounded by the cells meeting the grading · h neighbourhood of
    // the tool's edge parts: 2 (g + √2) s / h + π (g + √2)² cells per part of length s, 4
    // children each. A level that would take the total beyond edge_max_leaves (the model's
    // capacity) is not refined.
    const int last = std::min(def.max_level, level + def.edge_levels);
    std::int64_t leaves = 0;
    for (int l = level; l < last; ++l) {
      const double h = std::max(model.CellSizeX_m(l), model.CellSizeY_m(l));
      const double r = def.grading + std::numbers::sqrt2;
      double cells = 0;
      int parts = 0;
      ForEachEdgePart(
          model, zones, EdgeMargin_m(model, l), [&](double ax, double ay, double bx, double by) {
            cells += 2 * r * std::hypot(bx - ax, by - ay) / h + std::numbers::pi * r * r + 1;
            ++parts;
          });
      if (parts == 0) break;
      leaves += 4 * static_cast<std::int64_t>(std::ceil(cells));
      if (leaves > def.edge_max_leaves) break;
      zones.edge_finest = l + 1;
    }
  }
  return zones;
}

bool ClipSegmentToBox(double ax, double ay, double bx, double by, double x0, double y0, double x1,
                      double y1, double* t0, double* t1) {
  double lo = 0, hi = 1;
  const double d[2] = {bx - ax, by - ay};
  const double a[2] = {ax, ay};
  const double mins[2] = {x0, y0};
  const double maxs[2] = {x1, y1};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0) {
      if (a[k] < mins[k] || a[k] > maxs[k]) return false;
      continue;
    }
    double ta = (mins[k] - a[k]) / d[k];
    double tb = (maxs[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
    if (lo > hi) return false;
  }
  *t0 = lo;
  *t1 = hi;
  return true;
}

bool EdgeRefine(const TissueModel& model, const EndZones& zones, int l, int ci, int cj) {
  if (l >= zones.edge_finest) return false;
  const double hx = model.CellSizeX_m(l), hy = model.CellSizeY_m(l);
  const double x0 = ci * hx, y0 = cj * hy, x1 = x0 + hx, y1 = y0 + hy;
  const double reach = model.def.grading * std::max(hx, hy);
  bool near = false;
  ForEachEdgePart(
      model, zones, EdgeMargin_m(model, l), [&](double ax, double ay, double bx, double by) {
        near = near || SegmentBoxDistance2(ax, ay, bx, by, x0, y0, x1, y1) < reach * reach;
      });
  return near;
}

int LeafLevelOnTool(const TissueModel& model, const EndZones& zones, double x_m, double y_m) {
  int l = zones.level;
  while (l < std::max(zones.finest, zones.edge_finest)) {
    const int n = 1 << l;
    const int ci = std::clamp(static_cast<int>(x_m / model.CellSizeX_m(l)), 0, n - 1);
    const int cj = std::clamp(static_cast<int>(y_m / model.CellSizeY_m(l)), 0, n - 1);
    if (!EndRefine(model, zones, l, ci, cj) && !EdgeRefine(model, zones, l, ci, cj)) break;
    ++l;
  }
  return l;
}

void SelectMesh(const TissueModel& model, int level, MeshKind kind, const ToolContact& tool,
                MeshSelection& mesh) {
  MICRODEX_CHECK(level >= 1 && level <= model.def.level);
  mesh.zones = FindEndZones(model, level, kind, tool);
  if (++mesh.mark == 0) {  // wrapped: old marks could alias the new one
    std::fill(mesh.node_mark.begin(), mesh.node_mark.end(), 0u);
    mesh.mark = 1;
  }
  mesh.num_leaves = 0;
  mesh.num_triangles = 0;
  mesh.num_active_nodes = 0;
  mesh.level = level;
  mesh.signature = HashMix(kFnvOffset, static_cast<std::uint64_t>(level));
  Selector selector{model, level, kind, tool, mesh};
  for (int cj = 0; cj < 2; ++cj) {
    for (int ci = 0; ci < 2; ++ci) selector.Visit(1, ci, cj);
  }
  // A side's midpoint is a vertex of another leaf only if the neighbour across that side is
  // refined (the quadtree is 2:1 balanced, see TissueDef::grading), so it becomes a vertex of
  // this leaf too. Centres are marked after all tests: a centre never lies on another leaf's side.
  for (int k = 0; k < mesh.num_leaves; ++k) {
    Leaf& leaf = mesh.leaves[k];
    if (leaf.level >= model.def.max_level) continue;
    for (int side = 0; side < 4; ++side) {
      const int mid =
          CellVertex(model, leaf.level, leaf.ci, leaf.cj, kMidpoints[side].u, kMidpoints[side].v);
      if (mesh.node_mark[mid] == mesh.mark)
        leaf.hanging_mask |= static_cast<std::uint8_t>(1u << side);
    }
  }
  std::array<Triangle, 8> cell_triangles;
  for (int k = 0; k < mesh.num_leaves; ++k) {
    const Leaf& leaf = mesh.leaves[k];
    if (leaf.hanging_mask != 0)
      MarkNode(mesh, CellVertex(model, leaf.level, leaf.ci, leaf.cj, 1, 1));
    const int n = LeafTriangles(model, leaf, cell_triangles);
    MICRODEX_CHECK(mesh.num_triangles + n <= static_cast<int>(mesh.triangles.size()));
    std::copy_n(cell_triangles.begin(), n, mesh.triangles.begin() + mesh.num_triangles);
    mesh.num_triangles += n;
  }
}

}  // namespace microdex::fem
