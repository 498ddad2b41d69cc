#include "common/fem/tool_points.h"

#include <algorithm>
#include <cmath>

#include "common/base/check.h"

namespace microdex::fem {
namespace {

// Side s's midpoint of a cell in half-cell units (bottom, right, top, left).
constexpr std::array<TemplateVertex, 4> kSideMidpoints = {{{1, 0}, {2, 1}, {1, 2}, {0, 1}}};

bool IsZoneVertex(const EndZones& zones, const Eigen::Vector3d& p) {
  for (int v = 0; v < zones.num_vertices; ++v) {
    if (zones.x_m[v] == p.x() && zones.y_m[v] == p.y()) return true;
  }
  return false;
}

struct PointWriter {
  const TissueModel& model;
  std::span<ToolPoint> out;
  int count = 0;
  int previous = -1;  // the last point written, if the last candidate was kept

  // A candidate point of the tool, `gap_m` after the previous one along the tool: kept where it
  // is pressed (z < 0) and strictly inside the domain (the edges are clamped, w = 0, and take no
  // tool load). Each point stands for half the gap on either side. False when `out` is full.
  bool Emit(const Eigen::Vector3d& p, double dir_x, double dir_y, double gap_m) {
    if (previous >= 0) out[previous].length_m += 0.5 * gap_m;
    previous = -1;
    if (!(p.z() < 0)) return true;
    if (!(p.x() > 0 && p.x() < model.def.length_x_m && p.y() > 0 && p.y() < model.def.length_y_m))
      return true;
    if (count >= static_cast<int>(out.size())) return false;
    ToolPoint& point = out[count];
    point = ToolPoint{};
    point.x_m = p.x();
    point.y_m = p.y();
    point.u_m = p.z();
    point.dir_x = dir_x;
    point.dir_y = dir_y;
    point.length_m = 0.5 * gap_m;
    previous = count++;
    return true;
  }

  // The points of (s0, s1] on a–b (arc lengths of a segment of planar length len), evenly
  // spaced at most `step` apart.
  bool Stretch(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double len, double s0, double s1,
               double step) {
    if (!(s1 > s0)) return true;
    // The relative slack keeps the count of a stretch that is a whole number of steps stable
    // against rounding of the tool's coordinates.
    constexpr double kCountSlack = 1e-9;
    const int n = std::max(1, static_cast<int>(std::ceil((s1 - s0) / step - kCountSlack)));
    const double dir_x = (b.x() - a.x()) / len, dir_y = (b.y() - a.y()) / len;
    for (int i = 1; i <= n; ++i) {
      const double s = i == n ? s1 : s0 + (s1 - s0) * i / n;
      if (!Emit(a + (s / len) * (b - a), dir_x, dir_y, (s1 - s0) / n)) return false;
    }
    return true;
  }
};

}  // namespace

int PlaceToolPoints(const TissueModel& model, const EndZones& zones, int level,
                    const ToolContact& tool, double spacing, std::span<ToolPoint> out) {
  const double h_m = std::max(model.CellSizeX_m(level), model.CellSizeY_m(level));
  const double reach_m = model.def.grading * h_m;  // the end rule's reach at the nominal level
  PointWriter writer{model, out};
  if (tool.num_points < 2) return 0;
  {
    const Eigen::Vector3d& a = tool.p_SP[0];
    const Eigen::Vector3d& b = tool.p_SP[1];
    const double len = std::hypot(b.x() - a.x(), b.y() - a.y());
    if (!writer.Emit(a, len > 0 ? (b.x() - a.x()) / len : 1.0,
                     len > 0 ? (b.y() - a.y()) / len : 0.0, 0.0))
      return -1;
  }
  const double lx = model.def.length_x_m, ly = model.def.length_y_m;
  for (int k = 0; k + 1 < tool.num_points; ++k) {
    const Eigen::Vector3d& a = tool.p_SP[k];
    const Eigen::Vector3d& b = tool.p_SP[k + 1];
    const double len = std::hypot(b.x() - a.x(), b.y() - a.y());
    if (!(len > 0)) continue;  // a vertical or repeated vertex: its point is already there
    const double d0 = IsZoneVertex(zones, a) ? std::min(reach_m, 0.5 * len) : 0.0;
    const double d1 = IsZoneVertex(zones, b) ? std::min(reach_m, 0.5 * len) : 0.0;
    // Stretches of constant spacing: the end zones, and for each edge-graded level l the
    // parts of the segment within edge_resolution · h_l of an edge (the edge rule's S_l),
    // whose leaves are at level l + 1 at least. The refined cells reach on along the tool
    // (up to (grading + √2) · h_l) but spacing the points by them there was measured to
    // stiffen the bar (locking: +0.3 % for a bar ending 4 mm from an edge), so not.
    constexpr int kMaxEdgeLevels = 8;
    std::array<double, kMaxEdgeLevels> lo{}, hi{};  // outside [lo, hi]: in the extended S_l
    std::array<double, 4 + 2 * kMaxEdgeLevels> breaks{};
    int num_breaks = 0;
    breaks[num_breaks++] = 0;
    breaks[num_breaks++] = d0;
    breaks[num_breaks++] = len - d1;
    breaks[num_breaks++] = len;
    const int edge_levels = std::min(zones.edge_finest - zones.level, kMaxEdgeLevels);
    for (int j = 0; j < edge_levels; ++j) {
      const int l = zones.level + j;
      const double h_l = std::max(model.CellSizeX_m(l), model.CellSizeY_m(l));
      const double m = model.def.edge_resolution * h_l;
      double u0 = 0, u1 = 0;
      if (2 * m < std::min(lx, ly) &&
          ClipSegmentToBox(a.x(), a.y(), b.x(), b.y(), m, m, lx - m, ly - m, &u0, &u1)) {
        lo[j] = u0 > 0 ? u0 * len : -1.0;
        hi[j] = u1 < 1 ? u1 * len : 2 * len;
      } else {  // the whole segment is near an edge
        lo[j] = 2 * len;
        hi[j] = -1.0;
      }
      breaks[num_breaks++] = std::clamp(lo[j], 0.0, len);
      breaks[num_breaks++] = std::clamp(hi[j], 0.0, len);
    }
    std::sort(breaks.begin(), breaks.begin() + num_breaks);
    for (int i = 0; i + 1 < num_breaks; ++i) {
      const double s0 = breaks[i], s1 = breaks[i + 1];
      if (!(s1 > s0)) continue;
      const double mid = 0.5 * (s0 + s1);
      int l = mid < d0 || mid > len - d1 ? zones.finest : level;
      for (int j = 0; j < edge_levels; ++j) {
        if (mid < lo[j] || mid > hi[j]) l = std::max(l, zones.level + j + 1);
      }
      const double h_l = std::max(model.CellSizeX_m(l), model.CellSizeY_m(l));
      if (!writer.Stretch(a, b, len, s0, s1, spacing * h_l)) return -1;
    }
  }
  return writer.count;
}

void LocateToolPoint(const TissueModel& model, const MeshSelection& mesh, const ToolContact& tool,
                     ToolPoint& point) {
  const int l = LeafLevelOnTool(model, mesh.zones, point.x_m, point.y_m);
  const int n = 1 << l;
  const double hx = model.CellSizeX_m(l), hy = model.CellSizeY_m(l);
  Leaf leaf;
  leaf.ci = std::clamp(static_cast<int>(point.x_m / hx), 0, n - 1);
  leaf.cj = std::clamp(static_cast<int>(point.y_m / hy), 0, n - 1);
  leaf.level = static_cast<std::int8_t>(l);
  // A side has its midpoint as a vertex exactly when that node is in the mesh (the neighbour
  // across it is finer; a centre never lies on another leaf's side).
  if (l < model.def.max_level) {
    for (int side = 0; side < 4; ++side) {
      const int mid =
          CellVertex(model, l, leaf.ci, leaf.cj, kSideMidpoints[side].u, kSideMidpoints[side].v);
      if (mesh.IsActive(mid)) leaf.hanging_mask |= static_cast<std::uint8_t>(1u << side);
    }
  }
  std::array<Triangle, 8> triangles;
  const int count = LeafTriangles(model, leaf, triangles);
  // Local coordinates in half cells from the leaf's corner: the template vertices are exact.
  const double u = 2 * (point.x_m / hx - leaf.ci), v = 2 * (point.y_m / hy - leaf.cj);
  double best = -1e300;
  for (int t = 0; t < count; ++t) {
    const auto& shape = kTemplateTriangles[triangles[t].shape];
    const double u0 = shape[0].u, v0 = shape[0].v;
    const double u1 = shape[1].u - u0, v1 = shape[1].v - v0;
    const double u2 = shape[2].u - u0, v2 = shape[2].v - v0;
    const double det = u1 * v2 - u2 * v1;
    const double l1 = ((u - u0) * v2 - u2 * (v - v0)) / det;
    const double l2 = (u1 * (v - v0) - (u - u0) * v1) / det;
    const double l0 = 1 - l1 - l2;
    const double inside = std::min({l0, l1, l2});
    if (inside > best) {  // the triangle that contains the point (the most inside one)
      best = inside;
      point.node = triangles[t].node;
      point.lambda = {l0, l1, l2};
    }
  }
  constexpr double kInsideTol = -1e-9;  // a point on the tool is in a leaf of the mesh
  MICRODEX_CHECK(best >= kInsideTol);
  point.kink_m = 0;
  for (int a = 0; a < 3; ++a) {
    double z_m = 0;
    point.kink_m += point.lambda[a] * ToolClosestPoint_m(tool, model.NodeX_m(point.node[a]),
                                                         model.NodeY_m(point.node[a]), &z_m);
  }
}

double ToolPointSpring(const ToolPoint& point, double shear_modulus_Pa, double thickness_m,
                       double kink_factor, double cap_N_per_m) {
  const double consistent = kink_factor * 2 * shear_modulus_Pa * thickness_m * point.length_m;
  return consistent < cap_N_per_m * point.kink_m ? consistent / point.kink_m : cap_N_per_m;
}

}  // namespace microdex::fem
