#include "common/thread/thread_step.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "common/thread/thread_contacts.h"
#include "common/thread/thread_forces.h"
#include "common/thread/vector_clones.h"

namespace microdex::thread {
namespace {

int ExactPairCount(const ThreadModel& model, const ThreadWorkspace& w) {
  return std::min(w.num_self_contacts, model.exact_pair_capacity);
}

// The nodes of self contact c, their weights g (node motion to gap change) and the pair's
// normal: the contact's term in the implicit matrix is d g g^T (x) n n^T.
struct PairTerm {
  int node[4];
  double g[4];
  Eigen::Vector3d n;
};
PairTerm MakePairTerm(const SelfContact& sc) {
  return {{sc.link_a, sc.link_a + 1, sc.link_b, sc.link_b + 1},
          {1.0 - sc.s, sc.s, -(1.0 - sc.t), -sc.t},
          sc.n_W};
}

// A solve column of the low-rank terms: the contact's nodes and weights along dir, with grasped
// nodes' weights zeroed (their rows are identity rows holding a prescribed dv).
NodeColumn MakeSolveColumn(const PairTerm& t, const Eigen::Vector3d& dir,
                           const ThreadWorkspace& w) {
  NodeColumn c;
  c.count = 4;
  c.dir = dir;
  for (int k = 0; k < 4; ++k) {
    c.node[k] = t.node[k];
    c.weight[k] = w.grasp_slot[t.node[k]] >= 0 ? 0.0 : t.g[k];
  }
  return c;
}

// When there are more self contacts than the exact coupling or friction take, the deepest ones
// (largest force) go first. std::sort does not allocate.
void SortSelfContactsByDepth(const ThreadModel& model, ThreadWorkspace& w) {
  const int n = w.num_self_contacts;
  const int exact = model.exact_pair_capacity;
  const int friction = model.friction_self_capacity;
  if (!((exact > 0 && n > exact) || (friction > 0 && n > friction))) return;
  std::sort(w.self_contacts.begin(), w.self_contacts.begin() + n,
            [](const SelfContact& a, const SelfContact& b) { return a.gap_m < b.gap_m; });
}

// Carried contact forces (README, "Carried contact forces in a held knot"). A contact takes a
// carried force only if its normal is within ~25 degrees of the carried one (cos 0.9): a pair
// of links that turned about each other is a new contact. The force is capped at
// kCarriedForceCap times the contact law's force scale (20 mN for the 10-0 nylon, the hold's
// tension). Measured (README, "Carried contact forces in a held knot"): with 50 the knot-tying
// scene's surgeon's knot around its stitch is held with a tension error of 1.9 % (the servo
// alone: < 0.5 %); with 5 the tie matrix's square knot at 513 nodes, mu 0.3 slides 1.9 mm in
// its hold; 10 passes both.
constexpr double kCarriedNormalCos = 0.9;
constexpr double kCarriedForceCap = 10.0;

// Stage: the force each of the deepest self contacts takes from the state's carried list: the
// entry of its own pair of links, else of a pair next to it (either link one further along),
// each entry taken once.
void MatchCarriedContacts(const ThreadModel& model, ThreadWorkspace& w, const ThreadState& state) {
  w.num_self_carried = 0;
  if (!state.carry_contact_forces) return;
  const int n = std::min({w.num_self_contacts, model.friction_self_capacity, kMaxCarriedContacts});
  std::array<bool, kMaxCarriedContacts> taken{};
  for (int c = 0; c < n; ++c) {
    const SelfContact& sc = w.self_contacts[c];
    int best = -1;
    for (int k = 0; k < state.num_carried; ++k) {
      const CarriedContact& cc = state.carried[k];
      if (taken[k] || std::abs(cc.link_a - sc.link_a) > 1 || std::abs(cc.link_b - sc.link_b) > 1 ||
          cc.n_W.dot(sc.n_W) < kCarriedNormalCos) {
        continue;
      }
      if (best < 0 || (cc.link_a == sc.link_a && cc.link_b == sc.link_b)) best = k;
    }
    w.self_carried_N[c] = 0.0;
    if (best >= 0) {
      taken[best] = true;
      w.self_carried_N[c] = state.carried[best].force_N;
    }
  }
  w.num_self_carried = n;
}

// Stage: after the implicit motion, before the projection: each carried contact's force moves
// by the contact law's stiffness at the guard times how far the motion went past the guard
// gap (an Uzawa step of an augmented Lagrangian across steps: the force the knot needs builds
// up over a few steps, and the projection no longer has to undo the same overshoot every
// step). The list is committed with the step.
void UpdateCarriedContacts(const ThreadModel& model, ThreadWorkspace& w, const ThreadState& state) {
  w.num_carried_next = 0;
  if (!state.carry_contact_forces) return;
  const ThreadDef& def = model.def;
  const Eigen::Matrix3Xd& x = state.x_W;
  const double guard_gap = (def.guard_fraction - 1.0) * def.diameter_m;
  const double k_guard = ContactStiffness(def, guard_gap);
  const double cap = kCarriedForceCap * def.contact_force_N;
  for (int c = 0; c < w.num_self_carried; ++c) {
    const SelfContact& sc = w.self_contacts[c];
    const Eigen::Vector3d p_a = (1.0 - sc.s) * x.col(sc.link_a) + sc.s * x.col(sc.link_a + 1);
    const Eigen::Vector3d p_b = (1.0 - sc.t) * x.col(sc.link_b) + sc.t * x.col(sc.link_b + 1);
    const double gap = sc.n_W.dot(p_a - p_b) - 2.0 * model.radius_m;
    const double f = std::clamp(w.self_carried_N[c] + k_guard * (guard_gap - gap), 0.0, cap);
    if (!(f > 0.0)) continue;
    w.carried_next[w.num_carried_next++] = CarriedContact{sc.link_a, sc.link_b, sc.n_W, f};
  }
}

// Stage: the friction contacts of this step: two unit tangents per contact (the columns with all
// node weights: relative tangential velocity t^T sum_k g_k v_k) and the impulse bound
// mu f_n h, f_n the normal force (5.9) at the start of the step.
void PrepareFrictionContacts(const ThreadModel& model, double h, ThreadWorkspace& w,
                             ThreadState& state) {
  const ThreadDef& def = model.def;
  int nf = 0;
  auto add = [&](const int* nodes, const double* g, int count, const Eigen::Vector3d& n,
                 double bound) {
    if (nf >= model.friction_capacity || !(bound > 0.0)) return;
    const Eigen::Vector3d axis =
        std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d t1 = n.cross(axis).normalized();
    const Eigen::Vector3d t2 = n.cross(t1);
    for (int d = 0; d < 2; ++d) {
      NodeColumn& c = w.friction_columns[2 * nf + d];
      c.count = count;
      c.dir = d == 0 ? t1 : t2;
      for (int k = 0; k < count; ++k) {
        c.node[k] = nodes[k];
        c.weight[k] = g[k];
      }
    }
    w.friction_bound[nf] = bound;
    ++nf;
  };
  if (def.friction_coefficient > 0.0) {
    const int self = std::min(w.num_self_contacts, model.friction_self_capacity);
    for (int c = 0; c < self; ++c) {
      const PairTerm t = MakePairTerm(w.self_contacts[c]);
      const double carried = c < w.num_self_carried ? w.self_carried_N[c] : 0.0;
      add(t.node, t.g, 4, t.n,
          def.friction_coefficient *
              (ContactForceMagnitude(def, w.self_contacts[c].gap_m) + carried) * h);
    }
  }
  if (def.object_friction_coefficient > 0.0) {
    for (int c = 0; c < w.num_object_contacts; ++c) {
      const ObjectContact& oc = w.object_contacts[c];
      const int nodes[2] = {oc.link, oc.link + 1};
      const double g[2] = {1.0 - oc.s, oc.s};
      add(nodes, g, 2, oc.n_W,
          def.object_friction_coefficient * ContactForceMagnitude(def, oc.gap_m) * h);
    }
  }
  state.status.num_friction_contacts = nf;
  state.status.num_sliding_contacts = 0;
}

// out[j] += a[j] d0 + b[j] d1 for j < n (element-wise: the same bits at every vector width).
MICRODEX_VECTOR_CLONES
void AddTwoColumns(const double* __restrict a, const double* __restrict b, double d0, double d1,
                   int n, double* __restrict out) {
  for (int j = 0; j < n; ++j) out[j] += a[j] * d0 + b[j] * d1;
}

// Stage: Coulomb friction in the implicit system. dv is A^-1 b on entry (the banded part's
// solution; BeginCorrection holds the exact pairs' correction to it) and the step's velocity
// change with the pairs and friction on return; the friction impulses p (two per contact, in the
// tangent plane) change it by (A + U D U^T)^-1 T p, so the relative tangential velocities after the
// step are v_t = T^T (v + dv) + G p with G the Delassus operator of the implicit system. Projected
// Gauss-Seidel over the contacts: each contact takes the impulse that stops its slip, projected
// onto the disc |p_c| <= mu f_n h (stick inside, slide at the rim). The implicit system's G,
// not the node masses, is what resists: a node of a stiff chain is held by its neighbours.
void SolveFriction(ThreadWorkspace& w, ThreadState& state, Eigen::VectorXd& dv) {
  constexpr int kMaxSweeps = 50;
  constexpr double kTolerance = 1e-4;  // of the largest impulse bound, per sweep
  const int nf = state.status.num_friction_contacts;
  const int nt = 2 * nf;
  const Eigen::Map<const Eigen::VectorXd> v(state.v_W.data(), state.v_W.size());
  Eigen::MatrixXd& G = w.delassus;
  w.low_rank.Delassus(G);
  double max_bound = 0.0;
  for (int c = 0; c < nf; ++c) max_bound = std::max(max_bound, w.friction_bound[c]);
  // dv is A^-1 b: the exact pairs' correction (Woodbury) enters the velocities through H_TU.
  for (int j = 0; j < nt; ++j) {
    w.friction_vt[j] =
        w.friction_columns[j].Dot(v) + w.friction_columns[j].Dot(dv) - w.low_rank.CorrectionDot(j);
    w.friction_p[j] = 0.0;
  }
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double change = 0.0;
    for (int c = 0; c < nf; ++c) {
      const int i = 2 * c;
      const double g00 = G(i, i), g01 = G(i, i + 1), g11 = G(i + 1, i + 1);
      const double det = g00 * g11 - g01 * g01;
      if (!(det > 0.0) || !(g00 > 0.0)) continue;  // all its nodes grasped
      const double r0 = w.friction_vt[i], r1 = w.friction_vt[i + 1];
      double p0 = w.friction_p[i] - (g11 * r0 - g01 * r1) / det;
      double p1 = w.friction_p[i + 1] - (g00 * r1 - g01 * r0) / det;
      const double norm = std::hypot(p0, p1);
      const double bound = w.friction_bound[c];
      if (norm > bound) {
        p0 *= bound / norm;
        p1 *= bound / norm;
      }
      const double d0 = p0 - w.friction_p[i], d1 = p1 - w.friction_p[i + 1];
      if (d0 == 0.0 && d1 == 0.0) continue;
      AddTwoColumns(G.col(i).data(), G.col(i + 1).data(), d0, d1, nt, w.friction_vt.data());
      w.friction_p[i] = p0;
      w.friction_p[i + 1] = p1;
      change = std::max(change, std::hypot(d0, d1));
    }
    if (change <= kTolerance * max_bound) break;
  }
  int sliding = 0;
  for (int c = 0; c < nf; ++c) {
    const double norm = std::hypot(w.friction_p[2 * c], w.friction_p[2 * c + 1]);
    if (norm >= (1.0 - 1e-9) * w.friction_bound[c]) ++sliding;
  }
  state.status.num_sliding_contacts = sliding;
  w.low_rank.FinishCorrection(w.friction_p.head(nt), dv);
}

// Stage: friction after the explicit baseline step (5.2), per contact with the node masses
// (Bridson, Fedkiw & Anderson 2002): in an explicit step the velocity already carries h F / m,
// so stopping the slip with impulses distributed by inverse masses, capped at mu f_n h, is
// Coulomb friction. Positions follow (x = x_prev + h v); grasped nodes do not move and pass
// their share to the tool.
void ApplyExplicitFriction(const ThreadModel& model, double h, ThreadWorkspace& w,
                           ThreadState& state) {
  const int nf = state.status.num_friction_contacts;
  for (int c = 0; c < nf; ++c) {
    const NodeColumn& c1 = w.friction_columns[2 * c];
    const NodeColumn& c2 = w.friction_columns[2 * c + 1];
    double inv_mass = 0.0;
    for (int k = 0; k < c1.count; ++k) {
      if (w.grasp_slot[c1.node[k]] < 0) {
        inv_mass += c1.weight[k] * c1.weight[k] / model.mass_kg[c1.node[k]];
      }
    }
    if (!(inv_mass > 0.0)) continue;
    const Eigen::Map<const Eigen::VectorXd> v(state.v_W.data(), state.v_W.size());
    double p0 = -c1.Dot(v) / inv_mass;
    double p1 = -c2.Dot(v) / inv_mass;
    const double norm = std::hypot(p0, p1);
    if (norm > w.friction_bound[c]) {
      p0 *= w.friction_bound[c] / norm;
      p1 *= w.friction_bound[c] / norm;
      ++state.status.num_sliding_contacts;
    }
    const Eigen::Vector3d p_W = p0 * c1.dir + p1 * c2.dir;
    for (int k = 0; k < c1.count; ++k) {
      const int node = c1.node[k];
      const int slot = w.grasp_slot[node];
      if (slot >= 0) {
        state.grasps[slot].f_T_W += (c1.weight[k] / h) * p_W;
        continue;
      }
      const Eigen::Vector3d dv = (c1.weight[k] / model.mass_kg[node]) * p_W;
      state.v_W.col(node) += dv;
      state.x_W.col(node) += h * dv;
    }
  }
}

// Stage: forces at the start of the step (5.3) without damping; torques (5.6). When system is
// given, also h^2 K into it (stretch, bend) and the contact stiffness bounds into scratch.
void CalcForces(const ThreadModel& model, ThreadWorkspace& w, ThreadState& state, BandedSpd* system,
                double h2) {
  w.f_W.setZero();
  AddStretchForces(model, state.x_W, w.f_W, system, h2);
  AddBendForces(model, state.x_W, w.f_W, system, h2);
  AddTwistCouplingForces(model, state.x_W, state.q_rad, w.f_W);
  AddGravityForces(model, w.f_W);
  // The implicit step couples the first self contacts exactly (ExactPairCount); the explicit
  // baseline keeps the thesis's per-node contact damping for all of them.
  const int exact = system != nullptr ? ExactPairCount(model, w) : 0;
  AddContactForces(model, w, w.f_W, /*with_stiffness=*/true, exact);
  CalcTwistTorques(model, state.q_rad, w.tau_N_m);
}

// Stage: (5.2) semi-implicit Euler. Grasped nodes move to their target; the tool's force is
// what the node's equation of motion leaves over: f_T = (F - C v) - m a.
void IntegrateSemiImplicit(const ThreadModel& model, double h, ThreadWorkspace& w,
                           ThreadState& state) {
  for (int i = 0; i < model.num_nodes; ++i) {
    const double c = model.drag_N_s_per_m[i] + w.c_contact_N_s_per_m[i];
    const Eigen::Vector3d f = w.f_W.col(i) - c * state.v_W.col(i);  // (5.3) with (5.8)
    const int slot = w.grasp_slot[i];
    if (slot >= 0) {
      Grasp& g = state.grasps[slot];
      const Eigen::Vector3d v_new = (g.p_WT - state.x_W.col(i)) / h;
      g.f_T_W = f - model.mass_kg[i] * (v_new - state.v_W.col(i)) / h;
      state.v_W.col(i) = v_new;
      state.qdot_rad_per_s[i] = (g.roll_rad - state.q_rad[i]) / h;
    } else {
      state.v_W.col(i) += (h / model.mass_kg[i]) * f;
      const double tau = w.tau_N_m[i] - model.def.twist_drag_N_m_s * state.qdot_rad_per_s[i];
      state.qdot_rad_per_s[i] += h * tau / model.inertia_kg_m2[i];
    }
    state.x_W.col(i) += h * state.v_W.col(i);
    state.q_rad[i] += h * state.qdot_rad_per_s[i];
  }
}

// Stage: linearly implicit (backward) Euler,
//   (M + h C + h^2 K) dv = h (F - C v) - h^2 K v,   v += dv,   x += h v,
// K the clipped stretch Hessian, the small-angle bending stiffness and the contact bounds.
// Grasped nodes are eliminated (their dv is prescribed); the tool force is their row's residual.
// Its steps, in order, are the functions below.

// The velocity change that takes a grasped node to its tool point in one step.
Eigen::Vector3d PrescribedDv(const Grasp& g, const ThreadState& state, double h) {
  return (g.p_WT - state.x_W.col(g.node)) / h - state.v_W.col(g.node);
}

// A (holding h^2 K of stretch and bend) += the contact bounds + M + h C; b = h (F - C v) - h^2 K v.
void AssembleImplicitSystem(const ThreadModel& model, double h, ThreadWorkspace& w,
                            const ThreadState& state) {
  const int n = model.num_nodes;
  BandedSpd& A = w.system;
  Eigen::VectorXd& b = w.rhs;
  const Eigen::Map<const Eigen::VectorXd> v(state.v_W.data(), 3 * n);
  for (int i = 0; i < n; ++i) {
    if (w.c_contact_N_s_per_m[i] == 0.0 && w.k_contact.col(i).isZero()) continue;
    A.AddBlock(i, i, (h * h) * Eigen::Map<const Eigen::Matrix3d>(w.k_contact.col(i).data()));
  }
  A.Multiply(v, b);  // b = h^2 K v
  for (int i = 0; i < n; ++i) {
    const double c = model.drag_N_s_per_m[i] + w.c_contact_N_s_per_m[i];
    for (int r = 0; r < 3; ++r) {
      const int k = 3 * i + r;
      A.At(k, k) += model.mass_kg[i] + h * c;
      b[k] = h * (w.f_W(r, i) - c * v[k]) - b[k];
    }
  }
}

// Exactly coupled self contacts: A += d u u^T, b -= d (u^T v) u with u = g (x) n and
// d = h c + h^2 k (contact damping and stiffness of the pair, relative motion only). Columns
// of grasped nodes hold a prescribed dv: their part moves to the free rows' right-hand side.
// The d u u^T terms are not added to the banded A: they enter as low-rank terms at the solve.
// Returns the number of exactly coupled pairs.
int CoupleExactPairs(const ThreadModel& model, double h, ThreadWorkspace& w, ThreadState& state) {
  Eigen::VectorXd& b = w.rhs;
  const int m = ExactPairCount(model, w);
  state.status.num_exact_pairs = m;
  state.status.num_bound_pairs = w.num_self_contacts - m;
  for (int q = 0; q < m; ++q) {
    const PairTerm t = MakePairTerm(w.self_contacts[q]);
    const double d = h * model.def.contact_damping_N_s_per_m +
                     h * h * ContactStiffness(model.def, w.self_contacts[q].gap_m);
    w.pair_d[q] = d;
    double uv = 0.0, ug = 0.0;
    for (int k = 0; k < 4; ++k) {
      uv += t.g[k] * t.n.dot(state.v_W.col(t.node[k]));
      const int slot = w.grasp_slot[t.node[k]];
      if (slot >= 0) {
        ug += t.g[k] * t.n.dot(PrescribedDv(state.grasps[slot], state, h));
      }
    }
    for (int k = 0; k < 4; ++k) {
      const bool grasped = w.grasp_slot[t.node[k]] >= 0;
      b.segment<3>(3 * t.node[k]) -= (d * (uv + (grasped ? 0.0 : ug)) * t.g[k]) * t.n;
    }
  }
  return m;
}

// Calls row(slot, r, k, dv) for each row k = 3 node + r of each grasped node, dv the row's
// prescribed velocity change.
template <typename RowFn>
void ForEachGraspedRow(const ThreadState& state, double h, RowFn&& row) {
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    const Grasp& g = state.grasps[slot];
    if (g.node < 0) continue;
    const Eigen::Vector3d dvg = PrescribedDv(g, state, h);
    for (int r = 0; r < 3; ++r) row(slot, r, 3 * g.node + r, dvg[r]);
  }
}

// Grasped nodes: keep their unmodified rows for the reaction, move their prescribed dv's
// columns to the right-hand side, then decouple their rows (dv = the prescribed value). Three
// passes: the columns are read from the whole A before any row is decoupled (one pass per
// node costs more: measured 2.8 % of the step).
void EliminateGraspedNodes(const ThreadModel& model, double h, ThreadWorkspace& w,
                           const ThreadState& state) {
  const int p = model.half_bandwidth;
  const int last = 3 * model.num_nodes - 1;
  BandedSpd& A = w.system;
  Eigen::VectorXd& b = w.rhs;
  ForEachGraspedRow(state, h, [&](int slot, int r, int k, double /*dv*/) {
    for (int j = std::max(0, k - p); j <= std::min(last, k + p); ++j) {
      w.grasp_rows(3 * slot + r, j - k + p) = A.At(k, j);
    }
  });
  ForEachGraspedRow(state, h, [&](int /*slot*/, int /*r*/, int k, double dv) {
    for (int j = std::max(0, k - p); j <= std::min(last, k + p); ++j) {
      if (j != k && w.grasp_slot[j / 3] < 0) b[j] -= A.At(j, k) * dv;
    }
  });
  ForEachGraspedRow(state, h, [&](int slot, int r, int k, double dv) {
    w.grasp_rows(3 * slot + r, 2 * p + 1) = b[k];
    for (int j = std::max(0, k - p); j <= std::min(last, k + p); ++j) {
      if (j != k) A.At(k, j) = 0.0;
    }
    A.At(k, k) = 1.0;
    b[k] = dv;
  });
}

// Where to twist the banded factor for the low-rank columns: at the last of their first rows
// (each column's topmost node). Above it the multi-column solve skips each column's leading
// zeros, below it every column is solved, down to the last row any column touches only
// (BandedSpd::Factorize); -1 (no twist) without columns.
int TwistRow(std::span<const NodeColumn> cols) {
  int twist = -1;
  for (const NodeColumn& c : cols) {
    int first = -1;
    for (int k = 0; k < c.count; ++k) {
      if (c.weight[k] != 0.0 && (first < 0 || c.node[k] < first)) first = c.node[k];
    }
    twist = std::max(twist, 3 * first);
  }
  return twist;
}

// Factorises the banded system and solves it in place (w.rhs becomes dv), then adds the
// exactly coupled pairs and the friction as low-rank terms on top of the banded factor.
bool SolveImplicitSystem(int m, ThreadWorkspace& w, ThreadState& state) {
  BandedSpd& A = w.system;
  Eigen::VectorXd& dv = w.rhs;
  const int nf = state.status.num_friction_contacts;
  for (int q = 0; q < m; ++q) {
    w.columns[q] = MakeSolveColumn(MakePairTerm(w.self_contacts[q]), w.self_contacts[q].n_W, w);
  }
  for (int j = 0; j < 2 * nf; ++j) {
    w.columns[m + j] = w.friction_columns[j];
    NodeColumn& c = w.columns[m + j];
    for (int k = 0; k < c.count; ++k) {
      if (w.grasp_slot[c.node[k]] >= 0) c.weight[k] = 0.0;
    }
  }
  const std::span<const NodeColumn> cols(w.columns.data(), m + 2 * nf);
  if (!A.Factorize(TwistRow(cols))) return false;
  A.Solve(dv);
  if (m + nf > 0) {
    if (!w.low_rank.Prepare(A, cols, m, w.pair_d.data())) return false;
    if (nf > 0) {
      // The pairs' correction and the friction response in one banded solve.
      w.low_rank.BeginCorrection(dv);
      SolveFriction(w, state, dv);
    } else {
      w.low_rank.CorrectSolution(dv);
    }
  }
  return true;
}

// The force of each grasp on the thread, negated: what the tool feels. The grasped rows'
// residual (A dv - b) / h, the exactly coupled pairs' share on grasped nodes, and the friction
// impulses on grasped nodes.
void CalcGraspReactions(const ThreadModel& model, double h, int m, ThreadWorkspace& w,
                        ThreadState& state) {
  const int n = model.num_nodes;
  const int p = model.half_bandwidth;
  const Eigen::VectorXd& dv = w.rhs;
  const int nf = state.status.num_friction_contacts;
  // Reaction: r = (A dv - b)_g / h is what the tool pushes with; the thread pushes back.
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    Grasp& g = state.grasps[slot];
    if (g.node < 0) continue;
    for (int r = 0; r < 3; ++r) {
      const int k = 3 * g.node + r;
      double row = 0.0;
      for (int j = std::max(0, k - p); j <= std::min(3 * n - 1, k + p); ++j) {
        row += w.grasp_rows(3 * slot + r, j - k + p) * dv[j];
      }
      g.f_T_W[r] = -(row - w.grasp_rows(3 * slot + r, 2 * p + 1)) / h;
    }
  }
  // The grasped nodes' rows also hold the exactly coupled pairs' d u (u^T dv).
  for (int q = 0; q < m; ++q) {
    const PairTerm t = MakePairTerm(w.self_contacts[q]);
    double ud = 0.0;
    bool any = false;
    for (int k = 0; k < 4; ++k) {
      ud += t.g[k] * t.n.dot(dv.segment<3>(3 * t.node[k]));
      any = any || w.grasp_slot[t.node[k]] >= 0;
    }
    if (!any) continue;
    for (int k = 0; k < 4; ++k) {
      const int slot = w.grasp_slot[t.node[k]];
      if (slot >= 0) state.grasps[slot].f_T_W -= (w.pair_d[q] * ud * t.g[k] / h) * t.n;
    }
  }
  // Friction impulses on grasped nodes are carried by the tool.
  for (int j = 0; j < 2 * nf; ++j) {
    const NodeColumn& c = w.friction_columns[j];
    for (int k = 0; k < c.count; ++k) {
      const int slot = w.grasp_slot[c.node[k]];
      if (slot >= 0) state.grasps[slot].f_T_W += (c.weight[k] * w.friction_p[j] / h) * c.dir;
    }
  }
}

// Torsion (5.6), implicitly: (I + h c + h^2 Kq) dqdot = h (tau - c qdot) - h^2 Kq qdot, the
// grasped nodes' roll prescribed.
bool IntegrateTwist(const ThreadModel& model, double h, ThreadWorkspace& w, ThreadState& state) {
  const int n = model.num_nodes;
  BandedSpd& T = w.twist_system;
  Eigen::VectorXd& tb = w.twist_rhs;
  T.SetZero();
  for (int j = 0; j < model.num_links; ++j) {
    const double k = h * h * model.twist_k_N_m[j];
    T.At(j, j) += k;
    T.At(j + 1, j + 1) += k;
    T.At(j + 1, j) -= k;
  }
  T.Multiply(state.qdot_rad_per_s, tb);
  const double cq = model.def.twist_drag_N_m_s;
  for (int i = 0; i < n; ++i) {
    T.At(i, i) += model.inertia_kg_m2[i] + h * cq;
    tb[i] = h * (w.tau_N_m[i] - cq * state.qdot_rad_per_s[i]) - tb[i];
  }
  for (const Grasp& g : state.grasps) {
    if (g.node < 0) continue;
    const double dqd = (g.roll_rad - state.q_rad[g.node]) / h - state.qdot_rad_per_s[g.node];
    for (int j = std::max(0, g.node - 1); j <= std::min(n - 1, g.node + 1); ++j) {
      if (j == g.node || w.grasp_slot[j] >= 0) continue;
      tb[j] -= T.At(j, g.node) * dqd;
      T.At(j, g.node) = 0.0;
    }
  }
  for (const Grasp& g : state.grasps) {
    if (g.node < 0) continue;
    const double dqd = (g.roll_rad - state.q_rad[g.node]) / h - state.qdot_rad_per_s[g.node];
    for (int j = std::max(0, g.node - 1); j <= std::min(n - 1, g.node + 1); ++j) {
      if (j != g.node) T.At(g.node, j) = 0.0;
    }
    T.At(g.node, g.node) = 1.0;
    tb[g.node] = dqd;
  }
  if (!T.Factorize()) return false;
  T.Solve(tb);
  state.qdot_rad_per_s += tb;
  state.q_rad += h * state.qdot_rad_per_s;
  return true;
}

bool IntegrateLinearlyImplicit(const ThreadModel& model, double h, ThreadWorkspace& w,
                               ThreadState& state) {
  AssembleImplicitSystem(model, h, w, state);
  const int m = CoupleExactPairs(model, h, w, state);
  EliminateGraspedNodes(model, h, w, state);
  if (!SolveImplicitSystem(m, w, state)) return false;
  CalcGraspReactions(model, h, m, w, state);
  const Eigen::VectorXd& dv = w.rhs;
  for (int i = 0; i < model.num_nodes; ++i) {
    state.v_W.col(i) += dv.segment<3>(3 * i);
    state.x_W.col(i) += h * state.v_W.col(i);
  }
  return IntegrateTwist(model, h, w, state);
}

void RollBack(ThreadWorkspace& w, ThreadState& state) {
  state.x_W = w.x_prev_W;
  state.v_W.setZero();
  state.q_rad = w.q_prev_rad;
  state.qdot_rad_per_s.setZero();
  for (Grasp& g : state.grasps) g.f_T_W.setZero();
}

// Stage: the per-node grasp-slot map of the workspace, from the state's grasps.
void RefreshGraspSlots(const ThreadState& state, ThreadWorkspace& w) {
  w.grasp_slot.setConstant(-1);
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    const int node = state.grasps[slot].node;
    if (node >= 0) w.grasp_slot[node] = slot;
  }
}

// Stage: the contact projection of the step's motion (ProjectContacts), swept: where two links
// that may meet moved relative to each other by more than 2 kPartMove diameters in the step (a
// loop that snaps shut when the instrument holding it open is withdrawn, an end whipping out of
// a throw), the motion from x_prev to the integrator's x is projected in parts, each from the
// projected end of the one before with its own candidate pairs, so that no part moves a pair by
// more than that. Contacts are then constraints on the path, not only on its end: a strand
// cannot pass through another within one step, which a single projection at the end of a large
// move does not see (the candidate pairs and the sign of each pair's separation are taken at
// the start). The pairs that may meet come from the hierarchy at x_prev with every sphere grown
// by the largest deformation (a node's move less the thread's mean move: a rigid jump of the
// whole thread stays one part). Moves beyond kMaxParts parts are projected in one. Velocities
// follow the projected positions: v = (x - x_prev) / h.
constexpr double kPartMove = 0.4;
constexpr int kMaxParts = 32;
int CountProjectionParts(const ThreadModel& model, ThreadWorkspace& w, const ThreadState& state) {
  const int n = model.num_nodes;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) mean += state.x_W.col(i) - w.x_prev_W.col(i);
  mean /= n;
  double deform = 0.0;
  for (int i = 0; i < n; ++i) {
    deform = std::max(deform, (state.x_W.col(i) - w.x_prev_W.col(i) - mean).squaredNorm());
  }
  deform = std::sqrt(deform);
  const double part = 2.0 * kPartMove * model.def.diameter_m;  // relative move per part
  if (2.0 * deform <= part) return 1;
  const int found = FindSweptPairs(model, w.x_prev_W, deform, w);
  double relative = 0.0;
  for (int k = 0; k < found; ++k) {
    const LinkPair& pair = w.swept_pairs[k];
    for (const int a : {pair.a, pair.a + 1}) {
      for (const int b : {pair.b, pair.b + 1}) {
        const Eigen::Vector3d move =
            (state.x_W.col(a) - w.x_prev_W.col(a)) - (state.x_W.col(b) - w.x_prev_W.col(b));
        relative = std::max(relative, move.squaredNorm());
      }
    }
  }
  relative = std::sqrt(relative);
  // Beyond kMaxParts parts (a teleported or violently jerked grasp, metres per second) no
  // affordable number of parts keeps a pair's move below a diameter: one part, as for small
  // moves.
  const double needed = std::ceil(relative / part);
  const int parts = needed > 1.0 && needed <= kMaxParts ? static_cast<int>(needed) : 1;
  return parts;
}

void ProjectStep(const ThreadModel& model, std::span<const Collider> colliders, double h,
                 double strain_limit, ThreadWorkspace& w, ThreadState& state) {
  const int parts = CountProjectionParts(model, w, state);
  w.projection_parts = parts;
  ContactProjection total;
  if (parts == 1) {
    total = ProjectContacts(model, colliders, strain_limit, w.x_prev_W, w, state);
    w.projection_sweeps_total = w.projection_sweeps;
  } else {
    w.x_end_W = state.x_W;
    w.x_part_W = w.x_prev_W;
    int sweeps = 0, sweeps_total = 0;
    for (int k = 1; k <= parts; ++k) {
      state.x_W = w.x_part_W;
      FindPairStarts(model, w, state);
      // The part's motion: 1/parts of the integrator's, from where the last part was projected.
      state.x_W = w.x_part_W + (w.x_end_W - w.x_prev_W) / parts;
      const ContactProjection p =
          ProjectContacts(model, colliders, strain_limit, w.x_part_W, w, state);
      total.contact_corrections += p.contact_corrections;
      total.strain_corrections += p.strain_corrections;
      sweeps = std::max(sweeps, w.projection_sweeps);
      sweeps_total += w.projection_sweeps;
      w.x_part_W = state.x_W;
    }
    w.projection_sweeps = sweeps;
    w.projection_sweeps_total = sweeps_total;
  }
  state.status.guard_corrections += total.contact_corrections;
  state.status.strain_corrections += total.strain_corrections;
  if (total.contact_corrections + total.strain_corrections > 0) {
    for (int i = 0; i < model.num_nodes; ++i) {
      if (w.grasp_slot[i] < 0) state.v_W.col(i) = (state.x_W.col(i) - w.x_prev_W.col(i)) / h;
    }
  }
}

}  // namespace

void StepThreadWith(const ThreadModel& model, Integrator integrator, double h,
                    std::span<const Collider> colliders, ThreadWorkspace& w, ThreadState& state) {
  RefreshGraspSlots(state, w);
  w.x_prev_W = state.x_W;
  w.v_prev_W = state.v_W;
  w.q_prev_rad = state.q_rad;
  w.qdot_prev_rad_per_s = state.qdot_rad_per_s;
  FindThreadContacts(model, colliders, w, state);
  SortSelfContactsByDepth(model, w);
  MatchCarriedContacts(model, w, state);
  PrepareFrictionContacts(model, h, w, state);
  bool ok = true;
  if (integrator == Integrator::kSemiImplicitEuler) {
    CalcForces(model, w, state, nullptr, 0.0);
    IntegrateSemiImplicit(model, h, w, state);
    ApplyExplicitFriction(model, h, w, state);
  } else {
    w.system.SetZero();
    CalcForces(model, w, state, &w.system, h * h);
    ok = IntegrateLinearlyImplicit(model, h, w, state);
    if (!ok) ++state.status.factorization_failures;
  }
  if (ok) UpdateCarriedContacts(model, w, state);
  if (ok) {
    // Contacts and (implicit step only) link lengths in one projection: the strain limit's
    // moves along the links and the contacts' moves across them converge together.
    const double limit =
        integrator == Integrator::kLinearlyImplicitEuler ? model.def.strain_limit : 0.0;
    ProjectStep(model, colliders, h, limit, w, state);
    ok = state.x_W.allFinite() && state.v_W.allFinite() && state.q_rad.allFinite() &&
         state.qdot_rad_per_s.allFinite();
    if (!ok) ++state.status.nonfinite_resets;
  }
  if (!ok) RollBack(w, state);
  if (ok || !state.carry_contact_forces) {
    state.num_carried = ok ? w.num_carried_next : 0;
    std::copy_n(w.carried_next.begin(), state.num_carried, state.carried.begin());
  }
  state.status.max_strain = CalcMaxStrain(model, state.x_W);
  state.time_s += h;
  ++state.status.steps;
}

void StepThread(const ThreadModel& model, std::span<const Collider> colliders, ThreadWorkspace& w,
                ThreadState& state) {
  StepThreadWith(model, model.def.integrator, model.def.time_step_s, colliders, w, state);
}

}  // namespace microdex::thread
