#include "common/fem/tissue_step.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>

#include "common/base/check.h"

namespace microdex::fem {
namespace {

using Clock = std::chrono::steady_clock;

double Microseconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::micro>(b - a).count();
}

bool ToolIsFinite(const ToolContact& tool) {
  if (tool.num_points < 1 || tool.num_points > kMaxToolPoints) return false;
  if (!std::isfinite(tool.contact_radius_m) || tool.contact_radius_m < 0) return false;
  if (!tool.p_ST.allFinite()) return false;
  for (int k = 0; k < tool.num_points; ++k) {
    if (!tool.p_SP[k].allFinite()) return false;
  }
  return true;
}

// LSD radix sort of (rank << 32 | node) keys on the rank bits, 11 bits per pass (ranks are
// below 2^22 for max_level ≤ 10): a few µs for the ~10³ free nodes of a step, where
// std::sort took several times that.
void RadixSortKeys(std::uint64_t* keys, std::uint64_t* scratch, int n) {
  constexpr int kBits = 11;
  constexpr int kBuckets = 1 << kBits;
  std::uint64_t* from = keys;
  std::uint64_t* to = scratch;
  for (int shift = 32; shift < 32 + 2 * kBits; shift += kBits) {
    int count[kBuckets + 1] = {};
    for (int i = 0; i < n; ++i) ++count[((from[i] >> shift) & (kBuckets - 1)) + 1];
    for (int b = 0; b < kBuckets; ++b) count[b + 1] += count[b];
    for (int i = 0; i < n; ++i) to[count[(from[i] >> shift) & (kBuckets - 1)]++] = from[i];
    std::swap(from, to);
  }
  // Two passes: the sorted keys are back in `keys`.
}

// Reorders ws.dof_node[0, n) by the model's nested-dissection rank.
void OrderNestedDissection(const TissueModel& model, TissueWorkspace& ws, int n) {
  for (int i = 0; i < n; ++i) {
    const int node = ws.dof_node[i];
    ws.order_keys[i] =
        (static_cast<std::uint64_t>(model.nd_rank[node]) << 32) | static_cast<std::uint32_t>(node);
  }
  RadixSortKeys(ws.order_keys.data(), ws.order_scratch.data(), n);
  for (int i = 0; i < n; ++i) ws.dof_node[i] = static_cast<int>(ws.order_keys[i] & 0xffffffffu);
}

// Reorders ws.dof_node[0, n) by grid-node id (row-major on the finest grid; ids < 2^22 for
// max_level ≤ 10).
void OrderRowMajor(TissueWorkspace& ws, int n) {
  for (int i = 0; i < n; ++i) {
    const auto node = static_cast<std::uint32_t>(ws.dof_node[i]);
    ws.order_keys[i] = (static_cast<std::uint64_t>(node) << 32) | node;
  }
  RadixSortKeys(ws.order_keys.data(), ws.order_scratch.data(), n);
  for (int i = 0; i < n; ++i) ws.dof_node[i] = static_cast<int>(ws.order_keys[i] & 0xffffffffu);
}

std::uint64_t MixKey(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  return h * 1099511628211ull;
}

// The element matrices of the step's mesh under its map (ws.map): per leaf, the slopes of the
// map on the leaf's x and y ranges scale its templates' K_xx and K_yy (a leaf turned rigidly by
// the twist keeps them: the matrix is invariant under a rotation); a leaf across a breakpoint or
// in the twist's annulus has its triangles computed from their mapped vertices. False when a
// mapped triangle would fold (the map is then not used).
bool MapTriangles(const TissueModel& model, TissueWorkspace& ws) {
  const MeshSelection& mesh = ws.mesh;
  const TissueDef& def = model.def;
  int e = 0, general = 0;
  for (int k = 0; k < mesh.num_leaves; ++k) {
    const Leaf& leaf = mesh.leaves[k];
    const int count = leaf.hanging_mask == 0 ? 2 : 4 + std::popcount(leaf.hanging_mask);
    const double lx = model.CellSizeX_m(leaf.level), ly = model.CellSizeY_m(leaf.level);
    const double x0 = leaf.ci * lx, y0 = leaf.cj * ly;
    const double sx = ws.map.x.Slope(x0, x0 + lx), sy = ws.map.y.Slope(y0, y0 + ly);
    const bool sheared = ws.map.twist.Classify(x0, x0 + lx, y0, y0 + ly) == 2;
    for (int t = 0; t < count; ++t, ++e) {
      if (sx > 0 && sy > 0 && !sheared) {
        ws.tri_coef[e] = {sy / sx, sx / sy};
        ws.tri_general[e] = -1;
        continue;
      }
      const Triangle& tri = mesh.triangles[e];
      std::array<double, 3> xs{}, ys{};
      for (int v = 0; v < 3; ++v) {
        const TemplateVertex& tv = kTemplateTriangles[tri.shape][v];
        ws.map.ToPhysical(x0 + 0.5 * tv.u * lx, y0 + 0.5 * tv.v * ly, &xs[v], &ys[v]);
      }
      if (!CalcElementMatrix(xs, ys, def.shear_modulus_Pa, def.thickness_m, ws.general_k[general]))
        return false;
      ws.tri_general[e] = general++;
    }
  }
  MICRODEX_CHECK(e == mesh.num_triangles);
  return true;
}

// Triangle e's element matrix on this step's mesh; `scratch` holds it when it is scaled.
const ElementMatrix& TriangleMatrix(const TissueModel& model, const TissueWorkspace& ws, int e,
                                    ElementMatrix& scratch) {
  const Triangle& t = ws.mesh.triangles[e];
  if (!ws.mapped) return model.element_matrices[t.level][t.shape];
  if (ws.tri_general[e] >= 0) return ws.general_k[ws.tri_general[e]];
  const ElementMatrix& kxx = model.element_matrices_xx[t.level][t.shape];
  const ElementMatrix& kyy = model.element_matrices_yy[t.level][t.shape];
  const double cx = ws.tri_coef[e][0], cy = ws.tri_coef[e][1];
  for (int ab = 0; ab < 9; ++ab) scratch[ab] = cx * kxx[ab] + cy * kyy[ab];
  return scratch;
}

class ContactFinder {
 public:
  ContactFinder(const TissueModel& model, const ToolContact& tool, TissueWorkspace& ws)
      : model_(model), tool_(tool), ws_(ws) {}

  // Fills ws.contact_nodes / contact_w_m and tags them in node_dof. False on overflow.
  bool Run() {
    ws_.num_contacts = 0;
    const MeshSelection& mesh = ws_.mesh;
    const EndZones& zones = mesh.zones;
    const int level = mesh.level;
    const double hx = model_.CellSizeX_m(level), hy = model_.CellSizeY_m(level);
    const double lx = model_.def.length_x_m, ly = model_.def.length_y_m;
    const int stride = model_.Stride(level);
    const int cells = 1 << level;
    const double r = tool_.contact_radius_m;
    // Nearest node of points every half node spacing along each segment: a connected chain of
    // nodes under the tool whatever its orientation. Near an end-zone vertex the leaves are
    // finer: there the spacing is that of the finest zone level and the node is the nearest
    // one of the leaf containing the point (a corner of that leaf, so a mesh vertex).
    const double step_nominal_m = 0.5 * std::min(hx, hy);
    const double step_zone_m =
        0.5 * std::min(model_.CellSizeX_m(zones.finest), model_.CellSizeY_m(zones.finest));
    const double zone_reach_m = (model_.def.grading + 1.5) * std::max(hx, hy) + step_nominal_m;
    const int num_segments = std::max(1, tool_.num_points - 1);
    for (int k = 0; k < num_segments; ++k) {
      const Eigen::Vector3d& a = tool_.p_SP[k];
      const Eigen::Vector3d& b = tool_.p_SP[std::min(k + 1, tool_.num_points - 1)];
      double t0 = 0, t1 = 1;
      if (ClipSegmentToBox(a.x(), a.y(), b.x(), b.y(), 0, 0, lx, ly, &t0, &t1)) {
        const double len = (t1 - t0) * std::hypot(b.x() - a.x(), b.y() - a.y());
        for (double s = 0;;) {
          const bool last = s >= len;
          const double t = len > 0 ? t0 + (t1 - t0) * std::min(s, len) / len : t0;
          const double px = a.x() + t * (b.x() - a.x()), py = a.y() + t * (b.y() - a.y());
          bool near = false;
          for (int v = 0; v < zones.num_vertices; ++v) {
            const double dx = px - zones.x_m[v], dy = py - zones.y_m[v];
            near = near || dx * dx + dy * dy < zone_reach_m * zone_reach_m;
          }
          const int l = near ? LeafLevelOnTool(model_, zones, px, py) : level;
          const int cells_l = 1 << l, stride_l = model_.Stride(l);
          const int ci =
              std::clamp(static_cast<int>(std::lround(px / model_.CellSizeX_m(l))), 0, cells_l);
          const int cj =
              std::clamp(static_cast<int>(std::lround(py / model_.CellSizeY_m(l))), 0, cells_l);
          if (!Add(cj * stride_l * model_.nodes_per_side + ci * stride_l)) return false;
          if (last) break;
          s += near ? step_zone_m : step_nominal_m;
        }
      }
      if (r > 0) {  // every node within the contact radius of the segment
        const int i0 = std::max(1, static_cast<int>(std::ceil((std::min(a.x(), b.x()) - r) / hx)));
        const int i1 =
            std::min(cells - 1, static_cast<int>(std::floor((std::max(a.x(), b.x()) + r) / hx)));
        const int j0 = std::max(1, static_cast<int>(std::ceil((std::min(a.y(), b.y()) - r) / hy)));
        const int j1 =
            std::min(cells - 1, static_cast<int>(std::floor((std::max(a.y(), b.y()) + r) / hy)));
        for (int j = j0; j <= j1; ++j) {
          for (int i = i0; i <= i1; ++i) {
            double t = 0;
            const double px = i * hx, py = j * hy;
            const double dx = b.x() - a.x(), dy = b.y() - a.y();
            const double len2 = dx * dx + dy * dy;
            if (len2 > 0) t = std::clamp(((px - a.x()) * dx + (py - a.y()) * dy) / len2, 0.0, 1.0);
            if (std::hypot(px - a.x() - t * dx, py - a.y() - t * dy) > r) continue;
            if (!Add(j * stride * model_.nodes_per_side + i * stride)) return false;
          }
        }
      }
    }
    return true;
  }

 private:
  bool Add(int node) {
    const MeshSelection& mesh = ws_.mesh;
    if (model_.IsBoundaryNode(node) || !mesh.IsActive(node)) return true;
    if (ws_.contact_stamp[node] == mesh.mark) return true;  // already in the list
    double z_m = 0;
    ToolClosestPoint_m(tool_, model_.NodeX_m(node), model_.NodeY_m(node), &z_m);
    if (!(z_m < 0)) return true;  // the tool is not below the surface here
    if (ws_.num_contacts >= static_cast<int>(ws_.contact_nodes.size())) return false;
    const int c = ws_.num_contacts++;
    ws_.contact_nodes[c] = node;
    ws_.contact_w_m[c] = z_m;
    ws_.node_dof[node] = -2 - c;
    ws_.contact_stamp[node] = mesh.mark;
    return true;
  }

  const TissueModel& model_;
  const ToolContact& tool_;
  TissueWorkspace& ws_;
};

// The CSR pattern of K_ff and the slot of every element entry, without searching rows. The
// mesh is conforming and every triangle counter-clockwise, so a directed edge u→v belongs to
// exactly one triangle and its reverse v→u to the neighbour across it; every edge at a free
// node is interior. Row u therefore gets its diagonal plus one column per outgoing edge u→v,
// each exactly once. After sorting the short rows, the slot of (v, u) — the "twin" of (u, v)
// — is found by walking the rows in order: the columns below the diagonal of row v are
// sorted, so they are met in the order the rows u < v are visited. A triangle's entry
// (a, prev(a)) is then the twin of (prev(a), a), the outgoing edge of prev(a).
void BuildPattern(TissueWorkspace& ws, PatternEntry& entry, int n) {
  const MeshSelection& mesh = ws.mesh;
  for (int i = 0; i < n; ++i) {
    ws.row_fill[static_cast<size_t>(i) * kMaxRowEntries] = i;
    ws.row_count[i] = 1;
  }
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const int* d = &ws.tri_dof[3 * static_cast<size_t>(e)];
    int* place = &entry.scatter[9 * static_cast<size_t>(e)];
    for (int a = 0; a < 3; ++a) {
      const int b = a == 2 ? 0 : a + 1;
      place[a] = -1;  // place of the outgoing edge a→b in row_fill, kept in slots 0–2 for now
      if (d[a] < 0 || d[b] < 0) continue;
      int& count = ws.row_count[d[a]];
      MICRODEX_CHECK(count < kMaxRowEntries);
      ws.row_fill[static_cast<size_t>(d[a]) * kMaxRowEntries + count] = d[b];
      place[a] = d[a] * kMaxRowEntries + count++;
    }
  }
  int nnz = 0;
  for (int i = 0; i < n; ++i) {
    const int* row = &ws.row_fill[static_cast<size_t>(i) * kMaxRowEntries];
    const int count = ws.row_count[i];
    int order[kMaxRowEntries];
    for (int k = 0; k < count; ++k) {  // insertion sort of at most kMaxRowEntries indices
      int m = k;
      while (m > 0 && row[order[m - 1]] > row[k]) {
        order[m] = order[m - 1];
        --m;
      }
      order[m] = k;
    }
    entry.row_ptr[i] = nnz;
    int* rank = &ws.row_rank[static_cast<size_t>(i) * kMaxRowEntries];
    for (int p = 0; p < count; ++p) {
      const int col = row[order[p]];
      rank[order[p]] = p;
      if (col == i) entry.diag[i] = nnz + p;
      entry.cols[nnz + p] = col;
    }
    nnz += count;
  }
  entry.row_ptr[n] = nnz;
  std::fill_n(ws.row_count.begin(), n, 0);  // now: lower entries of each row matched so far
  for (int u = 0; u < n; ++u) {
    for (int p = entry.diag[u] + 1; p < entry.row_ptr[u + 1]; ++p) {
      const int v = entry.cols[p];
      const int q = entry.row_ptr[v] + ws.row_count[v]++;
      MICRODEX_CHECK(entry.cols[q] == u);  // the mesh is conforming
      ws.slot_twin[p] = q;
      ws.slot_twin[q] = p;
    }
  }
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const int* d = &ws.tri_dof[3 * static_cast<size_t>(e)];
    int* slots = &entry.scatter[9 * static_cast<size_t>(e)];
    int out[3];  // slot of the outgoing edge of each vertex
    for (int a = 0; a < 3; ++a) {
      const int place = slots[a];
      out[a] = place < 0 ? -1 : entry.row_ptr[place / kMaxRowEntries] + ws.row_rank[place];
    }
    for (int a = 0; a < 3; ++a) {
      const int next = a == 2 ? 0 : a + 1, prev = a == 0 ? 2 : a - 1;
      const bool free_a = d[a] >= 0;
      slots[3 * a + a] = free_a ? entry.diag[d[a]] : -1;
      slots[3 * a + next] = out[a];
      slots[3 * a + prev] = free_a && out[prev] >= 0 ? ws.slot_twin[out[prev]] : -1;
    }
  }
  entry.num_dofs = n;
  entry.valid = true;
  entry.values_valid = false;
  entry.factor_valid = false;
}

void AssembleValues(const TissueModel& model, const TissueWorkspace& ws, std::uint64_t map_hash,
                    PatternEntry& entry) {
  const MeshSelection& mesh = ws.mesh;
  std::fill_n(entry.vals.begin(), entry.row_ptr[entry.num_dofs], 0.0);
  ElementMatrix scratch;
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const ElementMatrix& k = TriangleMatrix(model, ws, e, scratch);
    const int* slots = &entry.scatter[9 * e];
    for (int ab = 0; ab < 9; ++ab) {
      if (slots[ab] >= 0) entry.vals[slots[ab]] += k[ab];
    }
  }
  entry.values_valid = true;
  entry.values_map_hash = map_hash;
  entry.factor_valid = false;
}

// b_f = −K_fc U_c: the prescribed displacements moved to the right-hand side, (3.10)–(3.11).
void AssembleRhs(const TissueModel& model, TissueWorkspace& ws, int n) {
  std::fill_n(ws.rhs.begin(), n, 0.0);
  const MeshSelection& mesh = ws.mesh;
  ElementMatrix scratch;
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const int* d = &ws.tri_dof[3 * static_cast<size_t>(e)];
    if (d[0] > -2 && d[1] > -2 && d[2] > -2) continue;  // no contact node in this element
    const ElementMatrix& k = TriangleMatrix(model, ws, e, scratch);
    for (int a = 0; a < 3; ++a) {
      if (d[a] < 0) continue;
      for (int b = 0; b < 3; ++b) {
        if (d[b] <= -2) ws.rhs[d[a]] -= k[3 * a + b] * ws.contact_w_m[-2 - d[b]];
      }
    }
  }
}

double NodeValue(const TissueWorkspace& ws, int dof_code) {
  if (dof_code >= 0) return ws.x[dof_code];
  if (dof_code == -1) return 0.0;
  return ws.contact_w_m[-2 - dof_code];
}

// The cap of a tool point's spring (where the tool runs on the mesh's lines), N/m.
double ToolPenalty_N_per_m(const TissueModel& model) {
  return model.def.tool_penalty * model.def.shear_modulus_Pa * model.def.thickness_m;
}

// The tool's points on this step's mesh (ToolConstraint::kPenaltyPoints). False on overflow.
bool FindToolPoints(const TissueModel& model, const ToolContact& tool, TissueWorkspace& ws) {
  ws.num_contacts = 0;
  ws.num_tool_points = 0;
  const int count = PlaceToolPoints(model, ws.mesh.zones, ws.mesh.level, tool,
                                    model.def.tool_point_spacing, ws.tool_points);
  if (count < 0) return false;
  const TissueDef& def = model.def;
  for (int k = 0; k < count; ++k) {
    ToolPoint& point = ws.tool_points[k];
    LocateToolPoint(model, ws.mesh, tool, point);
    point.spring_N_per_m = ToolPointSpring(point, def.shear_modulus_Pa, def.thickness_m,
                                           def.tool_kink_factor, ToolPenalty_N_per_m(model));
  }
  ws.num_tool_points = count;
  return true;
}

// Identifies the penalty matrix of the tool points (same nodes, same coordinates ⇒ same
// values), so a tool held still keeps its factor.
std::uint64_t HashToolPoints(const TissueWorkspace& ws) {
  std::uint64_t h = MixKey(0x7f4a7c15u, static_cast<std::uint64_t>(ws.num_tool_points));
  for (int k = 0; k < ws.num_tool_points; ++k) {
    const ToolPoint& p = ws.tool_points[k];
    for (int a = 0; a < 3; ++a) {
      h = MixKey(h, static_cast<std::uint64_t>(p.node[a]));
      h = MixKey(h, std::bit_cast<std::uint64_t>(p.lambda[a]));
    }
    h = MixKey(h, std::bit_cast<std::uint64_t>(p.spring_N_per_m));
  }
  return h;
}

// entry.tool_vals = K_ff + Σ_points β λ λᵀ (the penalty couples the three nodes of the point's
// triangle: entries of the mesh's own pattern).
void AssembleToolPenalty(TissueWorkspace& ws, PatternEntry& entry) {
  const int nnz = entry.row_ptr[entry.num_dofs];
  std::copy_n(entry.vals.begin(), nnz, entry.tool_vals.begin());
  for (int k = 0; k < ws.num_tool_points; ++k) {
    const ToolPoint& p = ws.tool_points[k];
    const double beta = p.spring_N_per_m;
    int d[3];
    for (int a = 0; a < 3; ++a) d[a] = ws.node_dof[p.node[a]];
    for (int a = 0; a < 3; ++a) {
      if (d[a] < 0) continue;
      for (int b = 0; b < 3; ++b) {
        if (d[b] < 0) continue;
        int slot = entry.diag[d[a]];
        if (b != a) {
          slot = entry.row_ptr[d[a]];
          while (entry.cols[slot] != d[b]) ++slot;  // a row has at most kMaxRowEntries
          MICRODEX_CHECK(slot < entry.row_ptr[d[a] + 1]);
        }
        entry.tool_vals[slot] += beta * p.lambda[a] * p.lambda[b];
      }
    }
  }
  entry.tool_vals_valid = true;
  entry.factor_valid = false;
}

// b_f = Σ_points β U λ: the springs pull the mesh towards the tool.
void AssembleToolRhs(TissueWorkspace& ws, int n) {
  std::fill_n(ws.rhs.begin(), n, 0.0);
  for (int k = 0; k < ws.num_tool_points; ++k) {
    const ToolPoint& p = ws.tool_points[k];
    for (int a = 0; a < 3; ++a) {
      const int d = ws.node_dof[p.node[a]];
      if (d >= 0) ws.rhs[d] += p.spring_N_per_m * p.u_m * p.lambda[a];
    }
  }
}

void Fail(TissueState& state, TissueStatus status) {
  state.status = status;
  ++state.num_failed_steps;
}

}  // namespace

const char* ToString(TissueStatus status) {
  switch (status) {
    case TissueStatus::kOk:
      return "ok";
    case TissueStatus::kNoContact:
      return "no_contact";
    case TissueStatus::kBadInput:
      return "bad_input";
    case TissueStatus::kTooManyContacts:
      return "too_many_contacts";
    case TissueStatus::kNotConverged:
      return "not_converged";
    case TissueStatus::kFactorisationFailed:
      return "factorisation_failed";
    case TissueStatus::kNonFinite:
      return "non_finite";
  }
  return "?";
}

TissueState MakeTissueState(const TissueModel& model) {
  TissueState state;
  state.field_nodes.assign(model.max_mesh_nodes, 0);
  state.field_w_m.assign(model.max_mesh_nodes, 0.0);
  state.leaves.resize(model.max_leaves);
  state.contact_nodes.resize(model.def.max_contact_nodes);
  state.contact_force_N.resize(model.def.max_contact_nodes);
  return state;
}

TissueWorkspace::TissueWorkspace(const TissueModel& model) : mesh(MakeMeshSelection(model)) {
  const int num_nodes = model.num_grid_nodes;
  const int n = model.max_mesh_nodes;  // bound on the free unknowns of a step
  node_dof.assign(num_nodes, -1);
  contact_stamp.assign(num_nodes, 0u);
  grid_w_m.assign(num_nodes, 0.0);
  grid_stamp.assign(num_nodes, 0u);
  dof_node.resize(n);
  order_keys.resize(n);
  order_scratch.resize(n);
  tri_dof.resize(3 * static_cast<size_t>(model.max_triangles));
  tri_coef.resize(model.max_triangles);
  tri_general.resize(model.max_triangles);
  general_k.resize(model.max_triangles);
  contact_nodes.resize(model.def.max_contact_nodes);
  contact_w_m.resize(model.def.max_contact_nodes);
  contact_f_N.resize(model.def.max_contact_nodes);
  tool_points.resize(std::max(1, model.def.max_contact_nodes / 3));
  contact_index.assign(num_nodes, 0);
  row_fill.resize(static_cast<size_t>(kMaxRowEntries) * n);
  row_rank.resize(static_cast<size_t>(kMaxRowEntries) * n);
  slot_twin.resize(static_cast<size_t>(kMaxRowEntries) * n);
  row_count.resize(n);
  rhs.resize(n);
  x.resize(n);
  residual.resize(n);
  patterns.resize(model.def.pattern_cache_entries);
  for (PatternEntry& entry : patterns) {
    entry.row_ptr.resize(n + 1);
    entry.cols.resize(static_cast<size_t>(kMaxRowEntries) * n);
    entry.vals.resize(static_cast<size_t>(kMaxRowEntries) * n);
    entry.tool_vals.resize(static_cast<size_t>(kMaxRowEntries) * n);
    entry.diag.resize(n);
    entry.dof_order.resize(n);
    entry.scatter.resize(static_cast<size_t>(9) * model.max_triangles);
  }
  cg = MakeCgWorkspace(n, kMaxRowEntries * n);
  cholmod = std::make_unique<CholmodSolver>(model.def.pattern_cache_entries,
                                            model.def.ordering == Ordering::kNestedDissection);
}

namespace {

// Select, after the mesh and the contacts: numbers the free nodes (boundary nodes fixed,
// contact nodes tagged by the finder) and returns their count; *key identifies the system's
// sparsity (mesh signature, contact count and nodes).
int NumberFreeNodes(const TissueModel& model, TissueWorkspace& ws, std::uint64_t* key) {
  const MeshSelection& mesh = ws.mesh;
  int n = 0;
  *key = MixKey(mesh.signature, static_cast<std::uint64_t>(ws.num_contacts));
  for (int k = 0; k < mesh.num_active_nodes; ++k) {
    const int node = mesh.active_nodes[k];
    if (ws.contact_stamp[node] == mesh.mark) continue;  // contact, tagged by the finder
    if (model.IsBoundaryNode(node)) {
      ws.node_dof[node] = -1;
    } else {
      ws.dof_node[n++] = node;
    }
  }
  for (int c = 0; c < ws.num_contacts; ++c) *key = MixKey(*key, ws.contact_nodes[c]);
  return n;
}

// The cached pattern of this selection, or a slot for a new one (least recently used), and
// the numbering of the unknowns: a cached pattern keeps the numbering it was built with.
int TakePatternSlot(const TissueModel& model, TissueWorkspace& ws, std::uint64_t key, int n,
                    bool* new_pattern) {
  const TissueDef& def = model.def;
  int slot = -1;
  for (int e = 0; e < static_cast<int>(ws.patterns.size()); ++e) {
    if (ws.patterns[e].valid && ws.patterns[e].key == key && ws.patterns[e].num_dofs == n) slot = e;
  }
  *new_pattern = slot < 0;
  if (*new_pattern) {
    slot = 0;
    for (int e = 1; e < static_cast<int>(ws.patterns.size()); ++e) {
      if (!ws.patterns[e].valid ||
          (ws.patterns[slot].valid && ws.patterns[e].last_used < ws.patterns[slot].last_used))
        slot = e;
    }
    if (ws.ic_valid && ws.ic_key == ws.patterns[slot].key) ws.ic_valid = false;
    ws.patterns[slot].key = key;
    // CHOLMOD keeps the unknowns in the order given: number them by nested-dissection rank,
    // so that a new pattern needs no ordering work (a sort of n keys instead of AMD).
    if (def.solver == SolverKind::kCholmod && def.ordering == Ordering::kNestedDissection)
      OrderNestedDissection(model, ws, n);
    // IC(0) and Jacobi take the unknowns in the grid's row-major order: measured against the
    // mesh's first-use (quadtree) order on the moving bar at level 7, IC(0)-PCG needs 22
    // iterations instead of 28 (−14 % instructions, −20 % L1 misses per step).
    if (def.solver != SolverKind::kCholmod) OrderRowMajor(ws, n);
    std::copy_n(ws.dof_node.begin(), n, ws.patterns[slot].dof_order.begin());
  } else {
    std::copy_n(ws.patterns[slot].dof_order.begin(), n, ws.dof_node.begin());
  }
  for (int i = 0; i < n; ++i) ws.node_dof[ws.dof_node[i]] = i;
  // The dof codes of every triangle's vertices, read once here (node_dof is a grid-sized
  // array: scattered reads) for the pattern, the right-hand side and the reactions.
  const MeshSelection& mesh = ws.mesh;
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const Triangle& t = mesh.triangles[e];
    for (int k = 0; k < 3; ++k) ws.tri_dof[3 * static_cast<size_t>(e) + k] = ws.node_dof[t.node[k]];
  }
  return slot;
}

// Solve with CHOLMOD: analysis per pattern, numeric factorisation per value change.
TissueStatus SolveCholmod(TissueWorkspace& ws, const CsrView& a, int slot, bool new_pattern,
                          PatternEntry& entry, TissueStepStats& stats) {
  stats.factor_reused = entry.factor_valid;
  if (!entry.factor_valid) {
    if (new_pattern || !ws.cholmod->HasAnalysis(slot)) ws.cholmod->Analyze(slot, a);
    entry.factor_valid = ws.cholmod->Factorize(slot, a);
  }
  if (!entry.factor_valid || !ws.cholmod->Solve(slot, ws.rhs.data(), ws.x.data(), a.n))
    return TissueStatus::kFactorisationFailed;
  return TissueStatus::kOk;
}

// The last good field at the point (x, y): bilinear on the finest grid cell around it whose
// four corners were nodes of that field's mesh (0 outside the domain).
double LastFieldAt(const TissueModel& model, const TissueWorkspace& ws, double x_m, double y_m) {
  if (!(x_m > 0 && x_m < model.def.length_x_m && y_m > 0 && y_m < model.def.length_y_m)) return 0;
  for (int l = model.def.max_level; l >= 1; --l) {
    const double u = x_m / model.CellSizeX_m(l), v = y_m / model.CellSizeY_m(l);
    const int cells = 1 << l;
    const int ci = std::min(static_cast<int>(u), cells - 1);
    const int cj = std::min(static_cast<int>(v), cells - 1);
    const int stride = model.Stride(l);
    const int n00 = (cj * model.nodes_per_side + ci) * stride;
    const int n10 = n00 + stride, n01 = n00 + stride * model.nodes_per_side, n11 = n01 + stride;
    if (ws.grid_stamp[n00] != ws.field_stamp || ws.grid_stamp[n10] != ws.field_stamp ||
        ws.grid_stamp[n01] != ws.field_stamp || ws.grid_stamp[n11] != ws.field_stamp)
      continue;
    const double fu = u - ci, fv = v - cj;
    return (1 - fv) * ((1 - fu) * ws.grid_w_m[n00] + fu * ws.grid_w_m[n10]) +
           fv * ((1 - fu) * ws.grid_w_m[n01] + fu * ws.grid_w_m[n11]);
  }
  return 0;
}

ToolPose PoseOf(const ToolContact& tool) {
  ToolPose pose{tool.p_SP[0].x(), tool.p_SP[0].y(), 0};
  if (tool.num_points >= 2)
    pose.angle_rad =
        std::atan2(tool.p_SP[1].y() - tool.p_SP[0].y(), tool.p_SP[1].x() - tool.p_SP[0].x());
  return pose;
}

// The starting point of (P)CG: the last good field carried along with the tool's rigid motion
// since that field's step (the field under a moving tool moves with it; where the tool holds
// still this is the last field itself), for the preconditioned solvers; else 0.
void StartFromLastField(const TissueModel& model, const TissueState& state, const ToolContact& tool,
                        TissueWorkspace& ws, int n) {
  const bool warm = model.def.solver != SolverKind::kCg && state.step > 0;
  if (warm) {
    ++ws.field_stamp;
    for (int k = 0; k < state.num_field_nodes; ++k) {
      const int node = state.field_nodes[k];
      ws.grid_w_m[node] = state.field_w_m[k];
      ws.grid_stamp[node] = ws.field_stamp;
    }
  }
  const ToolPose now = PoseOf(tool), then = state.field_tool_pose;
  const double turn = now.angle_rad - then.angle_rad;
  // Below a nanometre the carried field is the last one (a tool held still keeps its values).
  constexpr double kStill_m = 1e-9;
  const bool moved =
      warm && state.field_tool_pose_valid &&
      (std::abs(now.x_m - then.x_m) > kStill_m || std::abs(now.y_m - then.y_m) > kStill_m ||
       std::abs(turn) * model.def.length_x_m > kStill_m);
  if (moved) {
    const double c = std::cos(turn), s = std::sin(turn);
    for (int i = 0; i < n; ++i) {
      const int node = ws.dof_node[i];
      // The point that was at this node's place relative to the tool: R⁻¹ (x − now) + then.
      const double dx = model.NodeX_m(node) - now.x_m, dy = model.NodeY_m(node) - now.y_m;
      ws.x[i] = LastFieldAt(model, ws, then.x_m + c * dx + s * dy, then.y_m - s * dx + c * dy);
    }
    return;
  }
  int missing = 0;
  for (int i = 0; i < n; ++i) {
    const int node = ws.dof_node[i];
    const bool known = warm && ws.grid_stamp[node] == ws.field_stamp;
    ws.x[i] = known ? ws.grid_w_m[node] : 0.0;
    ws.row_count[i] = known ? 1 : 0;  // 1: value known (row_count is free scratch here)
    missing += known ? 0 : 1;
  }
  if (!warm || missing == 0) return;
  // Nodes new to this mesh (a fan gained a centre): the mean of their known neighbours, over
  // two sweeps of the triangles, instead of 0. Edge nodes and the tool's prescribed nodes
  // count as known.
  const MeshSelection& mesh = ws.mesh;
  for (int sweep = 0; sweep < 2; ++sweep) {
    std::fill_n(ws.residual.begin(), n, 0.0);
    std::fill_n(ws.order_keys.begin(), n, 0);  // neighbour counts
    for (int e = 0; e < mesh.num_triangles; ++e) {
      const int* d = &ws.tri_dof[3 * static_cast<size_t>(e)];
      for (int a = 0; a < 3; ++a) {
        if (d[a] < 0 || ws.row_count[d[a]] != 0) continue;
        for (int b = 0; b < 3; ++b) {
          if (b == a || (d[b] >= 0 && ws.row_count[d[b]] != 1)) continue;
          ws.residual[d[a]] += NodeValue(ws, d[b]);
          ++ws.order_keys[d[a]];
        }
      }
    }
    for (int i = 0; i < n; ++i) {
      if (ws.row_count[i] == 0 && ws.order_keys[i] > 0) {
        ws.x[i] = ws.residual[i] / static_cast<double>(ws.order_keys[i]);
        ws.row_count[i] = 2;  // filled this sweep: known from the next sweep on
      }
    }
    for (int i = 0; i < n; ++i) ws.row_count[i] = ws.row_count[i] == 2 ? 1 : ws.row_count[i];
  }
}

// Solve with CG, Jacobi-PCG, IC(0)-PCG or DIC-PCG (Eisenstat); the preconditioner is factored
// once per key.
TissueStatus SolveIterative(const TissueModel& model, const TissueState& state,
                            const ToolContact& tool, TissueWorkspace& ws, const CsrView& a,
                            std::uint64_t key, TissueStepStats& stats) {
  const TissueDef& def = model.def;
  StartFromLastField(model, state, tool, ws, a.n);
  if (def.solver != SolverKind::kCg) {
    stats.factor_reused = ws.ic_valid && ws.ic_key == key;
    if (!stats.factor_reused) {
      bool factored = false;
      switch (def.solver) {
        case SolverKind::kPcgJacobi:
          ws.ic_kind = Preconditioner::kJacobi;
          factored = FactorJacobi(a, ws.cg);
          break;
        case SolverKind::kPcgDic:
          // DIC exists for M-matrices; the tool points' springs can make K_ff something else,
          // and then IC(0) (its own pivots) is tried before the step is given up.
          ws.ic_kind = Preconditioner::kDic;
          factored = FactorDic(a, ws.cg, def.dic_relaxation);
          if (factored) break;
          [[fallthrough]];
        default:
          ws.ic_kind = Preconditioner::kIc0;
          factored = FactorIc0(a, ws.cg);
          break;
      }
      ws.ic_valid = factored;
      ws.ic_key = key;
      if (!factored) return TissueStatus::kFactorisationFailed;
    }
  }
  const Preconditioner preconditioner =
      def.solver == SolverKind::kCg ? Preconditioner::kNone : ws.ic_kind;
  stats.preconditioner = preconditioner;
  const CgResult cg = SolveCg(a, ws.rhs.data(), ws.x.data(), preconditioner,
                              def.cg_relative_tolerance, def.cg_max_iterations, ws.cg);
  stats.iterations = cg.iterations;
  return cg.converged ? TissueStatus::kOk : TissueStatus::kNotConverged;
}

// ‖b − K u‖ / ‖b‖, recomputed after the solve.
double RelativeResidual(const CsrView& a, TissueWorkspace& ws, double b_norm2) {
  Multiply(a, ws.x.data(), ws.residual.data());
  double r2 = 0;
  for (int i = 0; i < a.n; ++i) {
    const double r = ws.rhs[i] - ws.residual[i];
    r2 += r * r;
  }
  return std::sqrt(r2 / b_norm2);
}

// Solve the reduced system (3.9)–(3.11) for the free nodes.
TissueStatus SolveReduced(const TissueModel& model, const TissueState& state,
                          const ToolContact& tool, TissueWorkspace& ws, const CsrView& a,
                          std::uint64_t key, int slot, bool new_pattern, PatternEntry& entry,
                          TissueStepStats& stats) {
  const int n = a.n;
  const bool in_contact = ws.use_tool_points ? ws.num_tool_points > 0 : ws.num_contacts > 0;
  TissueStatus status = in_contact ? TissueStatus::kOk : TissueStatus::kNoContact;
  double b_norm2 = 0;
  for (int i = 0; i < n; ++i) b_norm2 += ws.rhs[i] * ws.rhs[i];
  if (n == 0) return status;
  if (b_norm2 == 0) {
    std::fill_n(ws.x.begin(), n, 0.0);
    return status;
  }
  const TissueStatus solved = model.def.solver == SolverKind::kCholmod
                                  ? SolveCholmod(ws, a, slot, new_pattern, entry, stats)
                                  : SolveIterative(model, state, tool, ws, a, key, stats);
  if (!IsGood(solved)) return solved;
  stats.relative_residual = RelativeResidual(a, ws, b_norm2);
  if (!std::isfinite(stats.relative_residual)) return TissueStatus::kNonFinite;
  return status;
}

// Reactions at the contact nodes (3.12): f_c = Σ_e K_e w over the elements around c; their
// resultant on the tool and its torque about tool.p_ST.
void CalcReactions(const TissueModel& model, const ToolContact& tool, TissueWorkspace& ws,
                   Eigen::Vector3d* f_T_S, Eigen::Vector3d* tau_T_S) {
  const MeshSelection& mesh = ws.mesh;
  std::fill_n(ws.contact_f_N.begin(), ws.num_contacts, 0.0);
  ElementMatrix scratch;
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const int* d = &ws.tri_dof[3 * static_cast<size_t>(e)];
    if (d[0] > -2 && d[1] > -2 && d[2] > -2) continue;
    const ElementMatrix& k = TriangleMatrix(model, ws, e, scratch);
    for (int a_local = 0; a_local < 3; ++a_local) {
      if (d[a_local] > -2) continue;
      double f = 0;
      for (int b = 0; b < 3; ++b) f += k[3 * a_local + b] * NodeValue(ws, d[b]);
      ws.contact_f_N[-2 - d[a_local]] += f;
    }
  }
  *f_T_S = Eigen::Vector3d::Zero();
  *tau_T_S = Eigen::Vector3d::Zero();
  for (int c = 0; c < ws.num_contacts; ++c) {
    const int node = ws.contact_nodes[c];
    const double fz_on_tool_N = -ws.contact_f_N[c];  // the tissue pushes back on the tool
    double px = 0, py = 0;
    ws.map.ToPhysical(model.NodeX_m(node), model.NodeY_m(node), &px, &py);
    const double rx = px - tool.p_ST.x(), ry = py - tool.p_ST.y();
    f_T_S->z() += fz_on_tool_N;
    tau_T_S->x() += ry * fz_on_tool_N;  // r × (0, 0, f)
    tau_T_S->y() -= rx * fz_on_tool_N;
  }
}

// Reactions of the tool points (ToolConstraint::kPenaltyPoints) at the nodes of their
// triangles, as (3.12): at a free node the elastic reaction Σ_e K_e w, which at equilibrium
// equals the springs' share Σ_p λ k (U − w_h) but does not amplify the solver's residual by
// the spring stiffness; at an edge node (clamped) the springs' share. Their resultant on the
// tool and its torque about tool.p_ST.
void CalcToolPointReactions(const TissueModel& model, const ToolContact& tool, TissueWorkspace& ws,
                            Eigen::Vector3d* f_T_S, Eigen::Vector3d* tau_T_S) {
  const MeshSelection& mesh = ws.mesh;
  const std::uint32_t mark = mesh.mark;
  ws.num_contacts = 0;
  for (int k = 0; k < ws.num_tool_points; ++k) {
    const ToolPoint& p = ws.tool_points[k];
    double w = 0;
    for (int a = 0; a < 3; ++a) w += p.lambda[a] * NodeValue(ws, ws.node_dof[p.node[a]]);
    const double f_on_tissue_N = p.spring_N_per_m * (p.u_m - w);
    for (int a = 0; a < 3; ++a) {
      if (p.lambda[a] == 0) continue;
      const int node = p.node[a];
      if (ws.contact_stamp[node] != mark) {
        ws.contact_stamp[node] = mark;
        ws.contact_index[node] = ws.num_contacts;
        ws.contact_nodes[ws.num_contacts] = node;
        ws.contact_f_N[ws.num_contacts] = 0;
        ++ws.num_contacts;
      }
      if (ws.node_dof[node] < 0)
        ws.contact_f_N[ws.contact_index[node]] += p.lambda[a] * f_on_tissue_N;
    }
  }
  ElementMatrix scratch;
  for (int e = 0; e < mesh.num_triangles; ++e) {
    const Triangle& t = mesh.triangles[e];
    const int* d = &ws.tri_dof[3 * static_cast<size_t>(e)];
    const ElementMatrix* k = nullptr;
    for (int a = 0; a < 3; ++a) {
      if (d[a] < 0 || ws.contact_stamp[t.node[a]] != mark) continue;
      if (k == nullptr) k = &TriangleMatrix(model, ws, e, scratch);
      double f = 0;
      for (int b = 0; b < 3; ++b) f += (*k)[3 * a + b] * NodeValue(ws, d[b]);
      ws.contact_f_N[ws.contact_index[t.node[a]]] += f;
    }
  }
  *f_T_S = Eigen::Vector3d::Zero();
  *tau_T_S = Eigen::Vector3d::Zero();
  for (int c = 0; c < ws.num_contacts; ++c) {
    const int node = ws.contact_nodes[c];
    const double fz_on_tool_N = -ws.contact_f_N[c];
    f_T_S->z() += fz_on_tool_N;
    double px = 0, py = 0;
    ws.map.ToPhysical(model.NodeX_m(node), model.NodeY_m(node), &px, &py);
    const double rx = px - tool.p_ST.x(), ry = py - tool.p_ST.y();
    tau_T_S->x() += ry * fz_on_tool_N;  // r × (0, 0, f)
    tau_T_S->y() -= rx * fz_on_tool_N;
  }
}

// This step is now the last good state.
void Commit(const TissueWorkspace& ws, const Eigen::Vector3d& f_T_S, const Eigen::Vector3d& tau_T_S,
            TissueStatus status, TissueState& state) {
  const MeshSelection& mesh = ws.mesh;
  ++state.step;
  for (int k = 0; k < mesh.num_active_nodes; ++k) {
    const int node = mesh.active_nodes[k];
    state.field_nodes[k] = node;
    state.field_w_m[k] = NodeValue(ws, ws.node_dof[node]);
  }
  state.num_field_nodes = mesh.num_active_nodes;
  std::copy_n(mesh.leaves.begin(), mesh.num_leaves, state.leaves.begin());
  state.num_leaves = mesh.num_leaves;
  std::copy_n(ws.contact_nodes.begin(), ws.num_contacts, state.contact_nodes.begin());
  std::copy_n(ws.contact_f_N.begin(), ws.num_contacts, state.contact_force_N.begin());
  state.num_contacts = ws.num_contacts;
  state.f_T_S = f_T_S;
  state.tau_T_S = tau_T_S;
  state.status = status;
}

}  // namespace

void StepTissue(const TissueModel& model, const ToolContact& tool_S, TissueWorkspace& ws,
                TissueState& state) {
  const Clock::time_point t_begin = Clock::now();
  TissueStepStats stats;
  // On failure: the stage times so far, the last good state kept, the status recorded.
  const auto fail = [&](TissueStatus status) {
    stats.total_us = Microseconds(t_begin, Clock::now());
    ws.stats = stats;
    Fail(state, status);
  };
  if (!ToolIsFinite(tool_S)) return fail(TissueStatus::kBadInput);

  // 0. The attached mesh: the map of this step and the tool in its reference plane, where the
  // mesh is chosen, the tool points placed and the system solved.
  MeshAnchor anchor = state.mesh_anchor;
  ws.map = model.def.attached_mesh ? AttachMesh(model, tool_S, anchor, &stats.mesh_reattached)
                                   : MeshMap{};
  ws.mapped = ws.map.Active();
  ToolContact tool_ref;
  if (ws.mapped) tool_ref = ToReference(ws.map, anchor, tool_S);

  // 1. Select: the mesh around the tool, the contact nodes, the numbering of the free nodes.
  SelectMesh(model, model.def.level, model.def.mesh, ws.mapped ? tool_ref : tool_S, ws.mesh);
  if (ws.mapped && !MapTriangles(model, ws)) {
    // A mapped triangle would fold: attach afresh at the tool (the identity map).
    anchor = MeshAnchor{};
    ws.map = AttachMesh(model, tool_S, anchor, &stats.mesh_reattached);
    stats.mesh_reattached = true;
    ws.mapped = false;
    SelectMesh(model, model.def.level, model.def.mesh, tool_S, ws.mesh);
  }
  const std::uint64_t map_hash = ws.mapped ? ws.map.Hash() : 0;
  stats.mesh_mapped = ws.mapped;
  stats.mesh_moved = ws.mapped && map_hash != state.field_map.Hash();
  const ToolContact& tool = ws.mapped ? tool_ref : tool_S;
  const MeshSelection& mesh = ws.mesh;
  ws.use_tool_points = model.def.tool_constraint == ToolConstraint::kPenaltyPoints &&
                       tool.num_points >= 2 && tool.contact_radius_m == 0;
  ws.num_tool_points = 0;
  ContactFinder finder(model, tool, ws);
  const bool contacts_fit = ws.use_tool_points ? FindToolPoints(model, tool, ws) : finder.Run();
  std::uint64_t key = 0;
  const int n = NumberFreeNodes(model, ws, &key);
  stats.unknowns = n;
  stats.contact_nodes = ws.use_tool_points ? ws.num_tool_points : ws.num_contacts;
  stats.active_nodes = mesh.num_active_nodes;
  stats.triangles = mesh.num_triangles;
  stats.leaves = mesh.num_leaves;
  if (!contacts_fit) {
    stats.select_us = Microseconds(t_begin, Clock::now());
    return fail(TissueStatus::kTooManyContacts);
  }
  bool new_pattern = false;
  const int slot = TakePatternSlot(model, ws, key, n, &new_pattern);
  const Clock::time_point t_selected = Clock::now();
  stats.select_us = Microseconds(t_begin, t_selected);

  // 2. Assemble: the pattern (new key only), K_ff's values (unless cached), b_f.
  if (new_pattern) BuildPattern(ws, ws.patterns[slot], n);
  PatternEntry& entry = ws.patterns[slot];
  entry.last_used = ++ws.use_clock;
  stats.pattern_reused = !new_pattern;
  const bool assembled =
      !entry.values_valid || !ws.reuse_values || entry.values_map_hash != map_hash;
  if (assembled) AssembleValues(model, ws, map_hash, entry);
  const double* vals = entry.vals.data();
  bool values_changed = assembled;
  if (ws.use_tool_points) {
    const std::uint64_t tool_hash = HashToolPoints(ws);
    if (assembled || !entry.tool_vals_valid || entry.tool_hash != tool_hash) {
      AssembleToolPenalty(ws, entry);
      entry.tool_hash = tool_hash;
      values_changed = true;
    }
    vals = entry.tool_vals.data();
    AssembleToolRhs(ws, n);
  } else {
    if (entry.tool_vals_valid) {  // the factor was of the penalised values
      entry.tool_vals_valid = false;
      entry.factor_valid = false;
      values_changed = true;
    }
    AssembleRhs(model, ws, n);
  }
  if (values_changed && ws.ic_key == key) ws.ic_valid = false;
  const CsrView a{n, entry.row_ptr.data(), entry.cols.data(), vals, entry.diag.data()};
  const Clock::time_point t_assembled = Clock::now();
  stats.assemble_us = Microseconds(t_selected, t_assembled);

  // 3. Solve.
  const TissueStatus status =
      SolveReduced(model, state, tool, ws, a, key, slot, new_pattern, entry, stats);
  const Clock::time_point t_solved = Clock::now();
  stats.solve_us = Microseconds(t_assembled, t_solved);
  if (!IsGood(status)) return fail(status);

  // 4. Forces, 5. commit.
  Eigen::Vector3d f_T_S, tau_T_S;
  if (ws.use_tool_points) {
    CalcToolPointReactions(model, tool_S, ws, &f_T_S, &tau_T_S);
  } else {
    CalcReactions(model, tool_S, ws, &f_T_S, &tau_T_S);
  }
  if (!f_T_S.allFinite() || !tau_T_S.allFinite()) return fail(TissueStatus::kNonFinite);
  // A re-attachment's step of the force, spread (TissueDef::reattach_blend_steps): the offset
  // from this solution to the last report, which shrinks linearly to nothing.
  const int blend_steps = model.def.reattach_blend_steps;
  // (Attaching afresh implies the last step was in contact on an attached mesh; state.f_T_S is
  // what it reported, kept through a failed step.)
  if (stats.mesh_reattached && blend_steps > 0) {
    state.blend_f_N = state.f_T_S + state.f_change_N - f_T_S;
    state.blend_tau_Nm = state.tau_T_S + state.tau_change_Nm - tau_T_S;
    state.blend_left = blend_steps;
  }
  if (status == TissueStatus::kNoContact) state.blend_left = 0;
  if (state.blend_left > 0) {
    const double w = static_cast<double>(state.blend_left) / std::max(blend_steps, 1);
    f_T_S += w * state.blend_f_N;
    tau_T_S += w * state.blend_tau_Nm;
    --state.blend_left;
    stats.force_blended = true;
  }
  const bool was_pressing = state.status == TissueStatus::kOk;
  state.f_change_N = was_pressing ? Eigen::Vector3d(f_T_S - state.f_T_S) : Eigen::Vector3d::Zero();
  state.tau_change_Nm =
      was_pressing ? Eigen::Vector3d(tau_T_S - state.tau_T_S) : Eigen::Vector3d::Zero();
  Commit(ws, f_T_S, tau_T_S, status, state);
  state.field_tool_pose = PoseOf(tool);
  state.field_tool_pose_valid = true;
  // Out of contact the mesh comes loose: the next contact attaches it where it begins.
  state.mesh_anchor = status == TissueStatus::kNoContact ? MeshAnchor{} : anchor;
  state.field_map = ws.map;
  const Clock::time_point t_end = Clock::now();
  stats.forces_us = Microseconds(t_solved, t_end);
  stats.total_us = Microseconds(t_begin, t_end);
  ws.stats = stats;
}

void ScatterField(const TissueState& state, std::vector<double>& grid_w_m) {
  for (int k = 0; k < state.num_field_nodes; ++k) {
    grid_w_m[state.field_nodes[k]] = state.field_w_m[k];
  }
}

void CalcDisplacementGrid(const TissueModel& model, const TissueState& state, int level,
                          std::vector<double>& grid_w_m, std::vector<double>& out_m) {
  MICRODEX_CHECK(level >= 0 && level <= 12);  // the display grid may be finer or coarser
  grid_w_m.resize(model.num_grid_nodes);
  ScatterField(state, grid_w_m);
  const int cells = 1 << level;
  const int side = cells + 1;
  out_m.assign(static_cast<size_t>(side) * side, 0.0);
  const double hx = model.CellSizeX_m(level), hy = model.CellSizeY_m(level);
  const MeshMap& map = state.field_map;
  std::array<Triangle, 8> tris;
  for (int k = 0; k < state.num_leaves; ++k) {
    const Leaf& leaf = state.leaves[k];
    const double lx = model.CellSizeX_m(leaf.level), ly = model.CellSizeY_m(leaf.level);
    const double x0 = leaf.ci * lx, y0 = leaf.cj * ly;
    const int count = LeafTriangles(model, leaf, tris);
    // The display nodes in a box holding the leaf's image under the field's map, interpolated
    // at their reference points (those outside the leaf fall in none of its triangles).
    double bx0 = 0, bx1 = 0, by0 = 0, by1 = 0;
    map.ImageBox(x0, x0 + lx, y0, y0 + ly, &bx0, &bx1, &by0, &by1);
    const int i0 = std::max(0, static_cast<int>(std::ceil(bx0 / hx - 1e-9)));
    const int i1 = std::min(cells, static_cast<int>(std::floor(bx1 / hx + 1e-9)));
    const int j0 = std::max(0, static_cast<int>(std::ceil(by0 / hy - 1e-9)));
    const int j1 = std::min(cells, static_cast<int>(std::floor(by1 / hy + 1e-9)));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        double px = 0, py = 0;
        map.ToReference(i * hx, j * hy, &px, &py);
        for (int t = 0; t < count; ++t) {
          const auto& nd = tris[t].node;
          const double xa = model.NodeX_m(nd[0]), ya = model.NodeY_m(nd[0]);
          const double xb = model.NodeX_m(nd[1]), yb = model.NodeY_m(nd[1]);
          const double xc = model.NodeX_m(nd[2]), yc = model.NodeY_m(nd[2]);
          const double det = (xb - xa) * (yc - ya) - (xc - xa) * (yb - ya);
          const double l1 = ((px - xa) * (yc - ya) - (xc - xa) * (py - ya)) / det;
          const double l2 = ((xb - xa) * (py - ya) - (px - xa) * (yb - ya)) / det;
          const double l0 = 1 - l1 - l2;
          constexpr double kInsideTol = -1e-9;
          if (l0 < kInsideTol || l1 < kInsideTol || l2 < kInsideTol) continue;
          out_m[static_cast<size_t>(j) * side + i] =
              l0 * grid_w_m[nd[0]] + l1 * grid_w_m[nd[1]] + l2 * grid_w_m[nd[2]];
          break;
        }
      }
    }
  }
}

}  // namespace microdex::fem
