#include "common/thread/thread_step.h"

#include <algorithm>

#include "common/thread/thread_contacts.h"
#include "common/thread/thread_forces.h"

namespace microdex::thread {
namespace {

// Stage: forces at the start of the step (5.3) without damping; torques (5.6). When system is
// given, also h^2 K into it (stretch, bend) and the contact stiffness bounds into scratch.
void CalcForces(const ThreadModel& model, ThreadState& state, BandedSpd* system, double h2) {
  ThreadScratch& w = state.scratch;
  w.f_W.setZero();
  AddStretchForces(model, state.x_W, w.f_W, system, h2);
  AddBendForces(model, state.x_W, w.f_W, system, h2);
  AddTwistCouplingForces(model, state.x_W, state.q_rad, w.f_W);
  AddGravityForces(model, w.f_W);
  AddContactForces(model, state, w.f_W, /*with_stiffness=*/true);
  CalcTwistTorques(model, state.q_rad, w.tau_N_m);
}

// Stage: (5.2) semi-implicit Euler. Grasped nodes move to their target; the tool's force is
// what the node's equation of motion leaves over: f_T = (F - C v) - m a.
void IntegrateSemiImplicit(const ThreadModel& model, double h, ThreadState& state) {
  ThreadScratch& w = state.scratch;
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
bool IntegrateLinearlyImplicit(const ThreadModel& model, double h, ThreadState& state) {
  ThreadScratch& w = state.scratch;
  const int n = model.num_nodes;
  const int p = model.half_bandwidth;
  BandedSpd& A = w.system;
  Eigen::VectorXd& b = w.rhs;
  const Eigen::Map<const Eigen::VectorXd> v(state.v_W.data(), 3 * n);
  // A currently holds h^2 K (stretch, bend); add the contact bounds.
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
  // Prescribed dv of grasped nodes; keep their unmodified rows for the reaction.
  Eigen::VectorXd& dv = b;  // solved in place
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    const Grasp& g = state.grasps[slot];
    if (g.node < 0) continue;
    for (int r = 0; r < 3; ++r) {
      const int k = 3 * g.node + r;
      for (int j = std::max(0, k - p); j <= std::min(3 * n - 1, k + p); ++j) {
        w.grasp_rows(3 * slot + r, j - k + p) = A.At(k, j);
      }
    }
  }
  // Eliminate: move prescribed columns to the right-hand side, then decouple the rows.
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    const Grasp& g = state.grasps[slot];
    if (g.node < 0) continue;
    const Eigen::Vector3d dvg = (g.p_WT - state.x_W.col(g.node)) / h - state.v_W.col(g.node);
    for (int r = 0; r < 3; ++r) {
      const int k = 3 * g.node + r;
      for (int j = std::max(0, k - p); j <= std::min(3 * n - 1, k + p); ++j) {
        if (j == k || w.grasp_slot[j / 3] >= 0) continue;
        b[j] -= A.At(j, k) * dvg[r];
      }
    }
  }
  for (int slot = 0; slot < static_cast<int>(state.grasps.size()); ++slot) {
    const Grasp& g = state.grasps[slot];
    if (g.node < 0) continue;
    const Eigen::Vector3d dvg = (g.p_WT - state.x_W.col(g.node)) / h - state.v_W.col(g.node);
    for (int r = 0; r < 3; ++r) {
      const int k = 3 * g.node + r;
      w.grasp_rows(3 * slot + r, 2 * p + 1) = b[k];
      for (int j = std::max(0, k - p); j <= std::min(3 * n - 1, k + p); ++j) {
        if (j != k) A.At(k, j) = 0.0;
      }
      A.At(k, k) = 1.0;
      b[k] = dvg[r];
    }
  }
  if (!A.Factorize()) return false;
  A.Solve(dv);
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
  for (int i = 0; i < n; ++i) {
    state.v_W.col(i) += dv.segment<3>(3 * i);
    state.x_W.col(i) += h * state.v_W.col(i);
  }
  // Torsion (5.6), implicitly: (I + h c + h^2 Kq) dqdot = h (tau - c qdot) - h^2 Kq qdot.
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

// Strain limiting (see ThreadDef::strain_limit): alternating Gauss-Seidel sweeps over the
// links, each moving a link's free end nodes along it in inverse proportion to their masses
// until its length is inside the band; grasped nodes do not move. Velocities follow the
// positions (x = x_prev + h v), as in the guard.
int LimitStrain(const ThreadModel& model, double h, ThreadState& state) {
  constexpr int kSweeps = 32;  // a correction travels one link per sweep; most steps need none
  const double limit = model.def.strain_limit;
  if (limit <= 0.0) return 0;
  Eigen::Matrix3Xd& x = state.x_W;
  const Eigen::VectorXi& grasped = state.scratch.grasp_slot;
  int corrections = 0;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    bool changed = false;
    for (int k = 0; k < model.num_links; ++k) {
      const int j = sweep % 2 == 0 ? k : model.num_links - 1 - k;
      const Eigen::Vector3d e = x.col(j + 1) - x.col(j);
      const double l = e.norm();
      const double r = model.rest_length_m[j];
      const double target = std::clamp(l, (1.0 - limit) * r, (1.0 + limit) * r);
      if (!(l > 0.0) || target == l) continue;
      const double w0 = grasped[j] >= 0 ? 0.0 : 1.0 / model.mass_kg[j];
      const double w1 = grasped[j + 1] >= 0 ? 0.0 : 1.0 / model.mass_kg[j + 1];
      if (!(w0 + w1 > 0.0)) continue;
      const Eigen::Vector3d corr = ((l - target) / (l * (w0 + w1))) * e;
      x.col(j) += w0 * corr;
      x.col(j + 1) -= w1 * corr;
      ++corrections;
      changed = true;
    }
    if (!changed) break;
  }
  if (corrections > 0) {
    for (int i = 0; i < model.num_nodes; ++i) {
      if (grasped[i] < 0) state.v_W.col(i) = (x.col(i) - state.scratch.x_prev_W.col(i)) / h;
    }
  }
  return corrections;
}

void RollBack(ThreadState& state) {
  ThreadScratch& w = state.scratch;
  state.x_W = w.x_prev_W;
  state.v_W.setZero();
  state.q_rad = w.q_prev_rad;
  state.qdot_rad_per_s.setZero();
  for (Grasp& g : state.grasps) g.f_T_W.setZero();
}

}  // namespace

void StepThreadWith(const ThreadModel& model, Integrator integrator, double h,
                    std::span<const Collider> colliders, ThreadState& state) {
  ThreadScratch& w = state.scratch;
  w.x_prev_W = state.x_W;
  w.v_prev_W = state.v_W;
  w.q_prev_rad = state.q_rad;
  w.qdot_prev_rad_per_s = state.qdot_rad_per_s;
  FindThreadContacts(model, colliders, state);
  bool ok = true;
  if (integrator == Integrator::kSemiImplicitEuler) {
    CalcForces(model, state, nullptr, 0.0);
    IntegrateSemiImplicit(model, h, state);
  } else {
    w.system.SetZero();
    CalcForces(model, state, &w.system, h * h);
    ok = IntegrateLinearlyImplicit(model, h, state);
    if (!ok) ++state.status.factorization_failures;
  }
  if (ok) {
    state.status.guard_corrections += ApplyNonPenetrationGuard(model, colliders, h, state);
    if (integrator == Integrator::kLinearlyImplicitEuler) {
      // After the guard: its projections stretch links too; the limit's moves along the
      // links are small and a second guard pass keeps the pairs apart.
      const int limited = LimitStrain(model, h, state);
      state.status.strain_corrections += limited;
      if (limited > 0) {
        state.status.guard_corrections += ApplyNonPenetrationGuard(model, colliders, h, state);
      }
    }
    ok = state.x_W.allFinite() && state.v_W.allFinite() && state.q_rad.allFinite() &&
         state.qdot_rad_per_s.allFinite();
    if (!ok) ++state.status.nonfinite_resets;
  }
  if (!ok) RollBack(state);
  state.status.max_strain = CalcMaxStrain(model, state.x_W);
  state.time_s += h;
  ++state.status.steps;
}

void StepThread(const ThreadModel& model, std::span<const Collider> colliders, ThreadState& state) {
  StepThreadWith(model, model.def.integrator, model.def.time_step_s, colliders, state);
}

}  // namespace microdex::thread
