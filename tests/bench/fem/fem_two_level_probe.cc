// microdex-bench fem --two-level-probe: how many iterations a two-level preconditioner would
// need on the moving bar's systems, before building one for speed. For steps of the bench's
// moving bar (level 7, pcg_ic), the step's system K_ff + penalty is solved from zero to the
// step's tolerance by IC(0)-PCG and by PCG with a symmetric two-level preconditioner: IC(0),
// a Galerkin coarse correction P (Pᵀ A P)⁻¹ Pᵀ on the bilinear functions of a uniform grid of
// level c (dense Cholesky: a measurement, not a fast path), IC(0) again; and IC(0) plus the
// coarse correction added. Counts only (−1: no convergence in 2 000). Coarse levels finer than
// the multi-scale mesh's far field make P rank-deficient there (several coarse functions on the
// same few fine nodes): Pᵀ A P is then singular.
#include "tests/bench/fem/fem_two_level_probe.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "common/fem/tissue_step.h"

namespace microdex::fem {
namespace {

void ApplyIc0(const CgWorkspace& ws, int n, const double* r, double* z) {
  const int* ptr = ws.l_ptr.data();
  const int* cols = ws.l_cols.data();
  const float* l = ws.l_vals.data();
  const double* inv = ws.inv_diag.data();
  for (int i = 0; i < n; ++i) {
    double s = r[i];
    for (int k = ptr[i]; k < ptr[i + 1]; ++k) s -= static_cast<double>(l[k]) * z[cols[k]];
    z[i] = s * inv[i];
  }
  for (int i = n - 1; i >= 0; --i) {
    z[i] *= inv[i];
    const double zi = z[i];
    for (int k = ptr[i]; k < ptr[i + 1]; ++k) z[cols[k]] -= static_cast<double>(l[k]) * zi;
  }
}

// PCG from zero; returns the iterations to ‖r‖ ≤ tol ‖b‖.
template <class Precondition>
int CountPcg(const CsrView& a, const Eigen::VectorXd& b, double tol, Precondition&& m) {
  const int n = a.n;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), r = b, z(n), p(n), q(n);
  m(r, z);
  p = z;
  double rz = r.dot(z);
  for (int it = 1; it <= 2000; ++it) {
    Multiply(a, p.data(), q.data());
    const double alpha = rz / p.dot(q);
    x += alpha * p;
    r -= alpha * q;
    if (r.norm() <= tol * b.norm()) return it;
    m(r, z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return -1;
}

}  // namespace

int RunTwoLevelProbe(const TissueModel& model, const std::vector<ToolContact>& tools) {
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  std::vector<double> it_ic, it_two[3];
  // Symmetric multiplicative at coarse level 3 and 4; additive (IC(0) + coarse, no extra
  // products with A) at level 3.
  const int coarse_levels[3] = {3, 4, 3};
  const bool additive[3] = {false, false, true};
  for (const ToolContact& tool : tools) {
    StepTissue(model, tool, ws, state);
    if (state.status != TissueStatus::kOk) continue;
    const PatternEntry* entry = nullptr;
    for (const PatternEntry& e : ws.patterns) {
      if (e.valid && e.last_used == ws.use_clock) entry = &e;
    }
    const int n = entry->num_dofs;
    const CsrView a{n, entry->row_ptr.data(), entry->cols.data(), entry->tool_vals.data(),
                    entry->diag.data()};
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) b[i] = ws.rhs[i];
    if (!FactorIc0(a, ws.cg)) continue;
    const double tol = model.def.cg_relative_tolerance;
    auto ic = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
      ApplyIc0(ws.cg, n, r.data(), z.data());
    };
    it_ic.push_back(CountPcg(a, b, tol, ic));
    for (int c = 0; c < 3; ++c) {
      const int level = coarse_levels[c];
      const int cells = 1 << level, side = cells - 1;
      const int nc = side * side;
      const double hx = model.CellSizeX_m(level), hy = model.CellSizeY_m(level);
      Eigen::MatrixXd p = Eigen::MatrixXd::Zero(n, nc);  // bilinear, interior coarse nodes
      for (int i = 0; i < n; ++i) {
        const int node = ws.dof_node[i];
        const double u = model.NodeX_m(node) / hx, v = model.NodeY_m(node) / hy;
        const int ci = std::min(static_cast<int>(u), cells - 1);
        const int cj = std::min(static_cast<int>(v), cells - 1);
        const double fu = u - ci, fv = v - cj;
        for (int dj = 0; dj < 2; ++dj) {
          for (int di = 0; di < 2; ++di) {
            const int I = ci + di, J = cj + dj;
            if (I < 1 || J < 1 || I > side || J > side) continue;
            p(i, (J - 1) * side + (I - 1)) += (di ? fu : 1 - fu) * (dj ? fv : 1 - fv);
          }
        }
      }
      Eigen::MatrixXd ap(n, nc);
      for (int k = 0; k < nc; ++k) {
        Eigen::VectorXd col = p.col(k);
        Multiply(a, col.data(), ap.col(k).data());
      }
      Eigen::MatrixXd ac = p.transpose() * ap;
      // Coarse nodes no fine node sees: keep the matrix positive definite.
      for (int k = 0; k < nc; ++k) {
        if (ac(k, k) == 0) ac(k, k) = 1;
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(ac);
      Eigen::VectorXd z1(n), t(n), z2(n);
      auto two = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
        if (additive[c]) {
          ApplyIc0(ws.cg, n, r.data(), z.data());
          z += p * llt.solve(p.transpose() * r);
          return;
        }
        ApplyIc0(ws.cg, n, r.data(), z1.data());
        Multiply(a, z1.data(), t.data());
        z1 += p * llt.solve(p.transpose() * (r - t));
        Multiply(a, z1.data(), t.data());
        Eigen::VectorXd r3 = r - t;
        ApplyIc0(ws.cg, n, r3.data(), z2.data());
        z = z1 + z2;
      };
      it_two[c].push_back(CountPcg(a, b, tol, two));
    }
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  };
  std::printf("two-level probe, level %d, %zu steps, PCG from zero to %.0e:\n", model.def.level,
              it_ic.size(), model.def.cg_relative_tolerance);
  std::printf("  IC(0): %.1f iterations (mean)\n", mean(it_ic));
  for (int c = 0; c < 3; ++c) {
    std::printf("  %s, Galerkin bilinear coarse level %d: %.1f iterations (mean)\n",
                additive[c] ? "IC(0) + coarse (additive)" : "IC(0), coarse, IC(0) (multiplicative)",
                coarse_levels[c], mean(it_two[c]));
  }
  return 0;
}

int RunContinuityProbe() {
  // The continuity motions of the report (level 7, pcg_dic, 400 steps at 1 kHz: translation at
  // 20 mm/s heading 0.5 rad, rotation at 1 rad/s about the centre), split into steps whose
  // multi-scale mesh is the previous one's and steps where it changed, for a few settings of
  // the tool points.
  struct Variant {
    const char* name;
    double spacing, kink_factor, grading;
  };
  const Variant variants[] = {{"default (spacing 1, kink 1.2, grading 2)", 1, 1.2, 2},
                              {"kink factor 1.0", 1, 1.0, 2},
                              {"kink factor 1.6", 1, 1.6, 2},
                              {"point spacing 0.5", 0.5, 1.2, 2},
                              {"grading 3", 1, 1.2, 3}};
  constexpr double kDomain_m = 0.2, kPress_m = 0.01;
  for (const Variant& v : variants) {
    TissueDef def;
    def.length_x_m = kDomain_m;
    def.length_y_m = kDomain_m;
    def.shear_modulus_Pa = 1e4;
    def.thickness_m = 0.01;
    def.max_level = 9;
    def.level = 7;
    def.solver = SolverKind::kPcgDic;
    def.cg_max_iterations = 100000;
    def.tool_point_spacing = v.spacing;
    def.tool_kink_factor = v.kink_factor;
    def.grading = v.grading;
    const TissueModel model = BuildTissueModel(def);
    for (int motion = 0; motion < 2; ++motion) {
      TissueWorkspace ws(model);
      TissueState state = MakeTissueState(model);
      double last_f = 0, max_same = 0, max_changed = 0, f_mean = 0;
      std::uint64_t last_signature = 0;
      int changes = 0;
      for (int k = 0; k < 400; ++k) {
        const double t = 1e-3 * k;
        double cx = 0.10, cy = 0.10, angle = 0.1 + t;
        if (motion == 0) {
          cx += 0.020 * t * std::cos(0.5);
          cy += 0.020 * t * std::sin(0.5);
          angle = 0;
        }
        const double dx = 0.05 * std::cos(angle), dy = 0.05 * std::sin(angle);
        StepTissue(model, MakeBarTool({cx - dx, cy - dy, -kPress_m}, {cx + dx, cy + dy, -kPress_m}),
                   ws, state);
        const double f = state.f_T_S.z();
        f_mean += std::abs(f) / 400;
        if (k > 0) {
          const double jump = std::abs(f - last_f) / std::abs(f);
          if (ws.mesh.signature == last_signature) {
            max_same = std::max(max_same, jump);
          } else {
            max_changed = std::max(max_changed, jump);
            ++changes;
          }
        }
        last_f = f;
        last_signature = ws.mesh.signature;
      }
      std::printf(
          "%-42s %-9s |F| %.4f N  largest step change / F: same mesh %.2e, mesh changed %.2e "
          "(%d changes)\n",
          v.name, motion == 0 ? "translate" : "rotate", f_mean, max_same, max_changed, changes);
    }
  }
  return 0;
}

}  // namespace microdex::fem
