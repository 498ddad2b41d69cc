#include "common/fem/tissue_step.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace microdex::fem {
namespace {

constexpr double kPress_m = 0.01;
constexpr double kSolverAgreementTol = 1e-6;  // relative, set by cg_relative_tolerance 1e-8

// The multi-scale mesh gets room for the default end grading (up to two levels beyond
// `level`; the 10 cm bars here end at level 7).
TissueModel Model(int level, MeshKind mesh, SolverKind solver, double g_Pa = 1e4,
                  ToolConstraint constraint = ToolConstraint::kPenaltyPoints) {
  TissueDef def;
  def.tool_constraint = constraint;
  def.max_level = mesh == MeshKind::kMultiscale ? level + 2 : level;
  def.level = level;
  def.mesh = mesh;
  def.solver = solver;
  def.shear_modulus_Pa = g_Pa;
  return BuildTissueModel(def);
}

ToolContact G1Bar(double depth_m) {
  return MakeBarTool({0.05, 0.10, -depth_m}, {0.15, 0.10, -depth_m});
}

struct Result {
  TissueStatus status;
  double force_N;
  Eigen::Vector3d tau;
  int contacts;
};

Result Step(const TissueModel& model, const ToolContact& tool) {
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  StepTissue(model, tool, ws, state);
  return {state.status, state.f_T_S.z(), state.tau_T_S, state.num_contacts};
}

// Manufactured solution w = sin(πx/L) sin(πy/B), p = G t π² (1/L² + 1/B²) w, assembled from
// the model's element tables on the fine mesh: nodal error falls as h².
TEST(TissueFem, ManufacturedSolutionConvergesSecondOrder) {
  double previous = 0;
  for (int level = 3; level <= 6; ++level) {
    TissueDef def;
    def.max_level = level;
    def.level = level;
    def.mesh = MeshKind::kFine;
    def.length_y_m = 0.12;
    const TissueModel model = BuildTissueModel(def);
    MeshSelection mesh = MakeMeshSelection(model);
    SelectMesh(model, level, MeshKind::kFine, ToolContact{}, mesh);
    const double lx = def.length_x_m, ly = def.length_y_m, pi = std::numbers::pi;
    auto exact = [&](double x, double y) { return std::sin(pi * x / lx) * std::sin(pi * y / ly); };
    const double p_scale =
        def.shear_modulus_Pa * def.thickness_m * pi * pi * (1 / (lx * lx) + 1 / (ly * ly));
    std::vector<int> dof(model.num_grid_nodes, -1);
    int n = 0;
    for (int id = 0; id < model.num_grid_nodes; ++id)
      if (!model.IsBoundaryNode(id)) dof[id] = n++;
    std::vector<Eigen::Triplet<double>> triplets;
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    for (int e = 0; e < mesh.num_triangles; ++e) {
      const Triangle& t = mesh.triangles[e];
      const ElementMatrix& k = model.element_matrices[t.level][t.shape];
      const double x[3] = {model.NodeX_m(t.node[0]), model.NodeX_m(t.node[1]),
                           model.NodeX_m(t.node[2])};
      const double y[3] = {model.NodeY_m(t.node[0]), model.NodeY_m(t.node[1]),
                           model.NodeY_m(t.node[2])};
      const double area = 0.5 * ((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
      for (int a = 0; a < 3; ++a) {
        if (dof[t.node[a]] < 0) continue;
        // Edge-midpoint quadrature (exact for quadratics) of ∫ p N_a.
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const double pab = exact(0.5 * (x[a] + x[b]), 0.5 * (y[a] + y[b]));
        const double pac = exact(0.5 * (x[a] + x[c]), 0.5 * (y[a] + y[c]));
        f[dof[t.node[a]]] += p_scale * area / 3 * 0.5 * (pab + pac);
        for (int bb = 0; bb < 3; ++bb)
          if (dof[t.node[bb]] >= 0)
            triplets.emplace_back(dof[t.node[a]], dof[t.node[bb]], k[3 * a + bb]);
      }
    }
    Eigen::SparseMatrix<double> kff(n, n);
    kff.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(kff);
    const Eigen::VectorXd w = solver.solve(f);
    double err = 0;
    for (int id = 0; id < model.num_grid_nodes; ++id)
      if (dof[id] >= 0)
        err = std::max(err, std::abs(w[dof[id]] - exact(model.NodeX_m(id), model.NodeY_m(id))));
    if (level > 3) {
      EXPECT_GT(previous / err, 3.5) << "level " << level;
      EXPECT_LT(previous / err, 4.5) << "level " << level;
    }
    previous = err;
  }
  EXPECT_LT(previous, 1e-3);
}

TEST(TissueStep, SolversAgreeOnFineAndMultiscaleMeshes) {
  for (MeshKind mesh : {MeshKind::kFine, MeshKind::kMultiscale}) {
    const double reference = Step(Model(5, mesh, SolverKind::kCholmod), G1Bar(kPress_m)).force_N;
    EXPECT_GT(reference, 0);  // pressed down, the tissue pushes the tool up
    for (SolverKind solver :
         {SolverKind::kCg, SolverKind::kPcgJacobi, SolverKind::kPcgIc, SolverKind::kPcgDic}) {
      const Result r = Step(Model(5, mesh, solver), G1Bar(kPress_m));
      ASSERT_EQ(r.status, TissueStatus::kOk);
      EXPECT_NEAR(r.force_N, reference, kSolverAgreementTol * reference) << ToString(solver);
    }
  }
  const double fine =
      Step(Model(6, MeshKind::kFine, SolverKind::kCholmod), G1Bar(kPress_m)).force_N;
  const double ms =
      Step(Model(6, MeshKind::kMultiscale, SolverKind::kCholmod), G1Bar(kPress_m)).force_N;
  EXPECT_NEAR(ms, fine, 0.02 * fine);
}

// Linear in G and in the prescribed displacement, from 1e-3 Pa to 1e9 Pa and from 0 to half
// the domain size.
TEST(TissueStep, StiffnessAndDisplacementSweepsStayLinearAndFinite) {
  const double base =
      Step(Model(5, MeshKind::kMultiscale, SolverKind::kCholmod), G1Bar(kPress_m)).force_N / 1e4;
  for (SolverKind solver :
       {SolverKind::kCholmod, SolverKind::kPcgIc, SolverKind::kPcgDic, SolverKind::kCg}) {
    for (double g : {1e-3, 1.0, 1e4, 1e6, 1e9}) {
      const Result r = Step(Model(5, MeshKind::kMultiscale, solver, g), G1Bar(kPress_m));
      ASSERT_EQ(r.status, TissueStatus::kOk) << g;
      EXPECT_NEAR(r.force_N / g, base, 1e-6 * base) << "G " << g << " " << ToString(solver);
    }
  }
  const TissueModel model = Model(5, MeshKind::kMultiscale, SolverKind::kCholmod);
  const Result half = Step(model, G1Bar(0.10));
  EXPECT_NEAR(half.force_N, 10 * base * 1e4, 1e-9 * half.force_N);
  const Result zero = Step(model, G1Bar(0.0));
  EXPECT_EQ(zero.status, TissueStatus::kNoContact);
  EXPECT_EQ(zero.force_N, 0.0);
  EXPECT_EQ(zero.contacts, 0);
}

// The reduced stiffness K_ff the step assembles (CSR pattern built from the mesh's directed
// edges, element entries scattered to slots) equals a plain triplet assembly of the same
// triangles, for a bar with end grading and an oblique polyline.
TEST(TissueStep, AssembledStiffnessMatchesTripletAssembly) {
  const Eigen::Vector3d polyline[] = {
      {0.031, 0.077, -0.01}, {0.112, 0.141, -0.012}, {0.17, 0.09, -0.008}};
  const ToolContact tools[] = {G1Bar(kPress_m), MakePolylineTool(polyline, 0.0)};
  for (const ToolContact& tool : tools) {
    const TissueModel model = Model(5, MeshKind::kMultiscale, SolverKind::kCholmod);
    TissueWorkspace ws(model);
    TissueState state = MakeTissueState(model);
    StepTissue(model, tool, ws, state);
    ASSERT_EQ(state.status, TissueStatus::kOk);
    const PatternEntry* entry = nullptr;
    for (const PatternEntry& p : ws.patterns)
      if (p.valid && p.last_used == ws.use_clock) entry = &p;
    ASSERT_NE(entry, nullptr);
    const int n = entry->num_dofs;
    std::vector<Eigen::Triplet<double>> triplets;
    for (int e = 0; e < ws.mesh.num_triangles; ++e) {
      const Triangle& t = ws.mesh.triangles[e];
      const ElementMatrix& k = model.element_matrices[t.level][t.shape];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const int da = ws.node_dof[t.node[a]], db = ws.node_dof[t.node[b]];
          if (da >= 0 && db >= 0) triplets.emplace_back(da, db, k[3 * a + b]);
        }
    }
    Eigen::SparseMatrix<double, Eigen::RowMajor> reference(n, n);
    reference.setFromTriplets(triplets.begin(), triplets.end());
    reference.makeCompressed();
    ASSERT_EQ(entry->row_ptr[n], reference.nonZeros());
    const double scale = model.def.shear_modulus_Pa * model.def.thickness_m;
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(entry->row_ptr[i + 1] - entry->row_ptr[i],
                reference.outerIndexPtr()[i + 1] - reference.outerIndexPtr()[i]);
      for (int p = entry->row_ptr[i]; p < entry->row_ptr[i + 1]; ++p) {
        const int q = reference.outerIndexPtr()[i] + (p - entry->row_ptr[i]);
        ASSERT_EQ(entry->cols[p], reference.innerIndexPtr()[q]) << "row " << i;
        EXPECT_NEAR(entry->vals[p], reference.valuePtr()[q], 1e-12 * scale) << "row " << i;
      }
      EXPECT_EQ(entry->cols[entry->diag[i]], i);
    }
  }
}

// With end grading the chain of contact nodes follows the leaves: every mesh vertex on a
// bar that lies on a grid line is a contact node (none is left free under the tool), the
// finer vertices near the ends included.
// The nearest-node constraint (the thesis's): every mesh vertex under the bar is prescribed.
TEST(TissueStep, ContactChainCoversEveryVertexUnderTheBar) {
  const TissueModel model =
      Model(5, MeshKind::kMultiscale, SolverKind::kCholmod, 1e4, ToolConstraint::kNearestNodes);
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  StepTissue(model, G1Bar(kPress_m), ws, state);
  ASSERT_EQ(state.status, TissueStatus::kOk);
  int on_bar = 0;
  for (int k = 0; k < ws.mesh.num_active_nodes; ++k) {
    const int node = ws.mesh.active_nodes[k];
    const double x = model.NodeX_m(node), y = model.NodeY_m(node);
    if (std::abs(y - 0.10) > 1e-12 || x < 0.05 - 1e-12 || x > 0.15 + 1e-12) continue;
    ++on_bar;
    EXPECT_LE(ws.node_dof[node], -2) << "free vertex under the bar at x = " << x;
  }
  // 17 nominal-level nodes, and at least 2 finer ones per end per extra level inside the bar
  // (the zone reaches two cells of each extra level inwards; cells at exactly that distance
  // are refined or not by rounding).
  ASSERT_EQ(ws.mesh.zones.finest, 7);  // 10 cm / 64 = 1.5625 mm, the level-7 cell
  EXPECT_GE(on_bar, 17 + 2 * 2 * (7 - 5));
  EXPECT_EQ(state.num_contacts, on_bar);
}

TEST(TissueStep, BarTouchingTheBoundaryAndLeavingTheDomain) {
  const TissueModel model = Model(6, MeshKind::kMultiscale, SolverKind::kCholmod);
  const Result touching = Step(model, MakeBarTool({0.0, 0.10, -kPress_m}, {0.10, 0.10, -kPress_m}));
  ASSERT_EQ(touching.status, TissueStatus::kOk);
  EXPECT_TRUE(std::isfinite(touching.force_N));
  EXPECT_GT(touching.force_N, 0);
  {  // held along its row only (finer by the edges: edge grading), at no node outside
    TissueWorkspace ws(model);
    TissueState state = MakeTissueState(model);
    StepTissue(model, MakeBarTool({-0.1, 0.05, -kPress_m}, {0.3, 0.05, -kPress_m}), ws, state);
    ASSERT_EQ(state.status, TissueStatus::kOk);
    int level_nodes = 0;  // the row's interior nodes of the level-6 grid, all held
    for (int c = 0; c < state.num_contacts; ++c) {
      const int node = state.contact_nodes[c];
      EXPECT_EQ(model.NodeY_m(node), 0.05);
      EXPECT_GE(model.NodeX_m(node), 0.0);
      EXPECT_LE(model.NodeX_m(node), 0.20);
      const double i = model.NodeX_m(node) / model.CellSizeX_m(6);
      level_nodes += !model.IsBoundaryNode(node) && std::abs(i - std::round(i)) < 1e-9;
    }
    EXPECT_EQ(level_nodes, 63);
  }
  const Result outside = Step(model, MakeBarTool({0.25, 0.1, -kPress_m}, {0.35, 0.1, -kPress_m}));
  EXPECT_EQ(outside.status, TissueStatus::kNoContact);
  EXPECT_EQ(outside.force_N, 0.0);
}

// The point load is singular: with a point contact the force needed for a given displacement
// falls as the mesh is refined (like 1/ln(1/h)); a finite contact radius regularises it.
TEST(TissueStep, PointToolSingularityAndItsRegularisation) {
  const Eigen::Vector3d p{0.1, 0.1, -kPress_m};
  double point[9] = {}, disc[9] = {};
  for (int level = 4; level <= 8; ++level) {
    const TissueModel model = Model(level, MeshKind::kMultiscale, SolverKind::kCholmod);
    point[level] = Step(model, MakePointTool(p, 0.0)).force_N;
    disc[level] = Step(model, MakePointTool(p, 0.01)).force_N;
  }
  for (int level = 5; level <= 8; ++level) EXPECT_LT(point[level], 0.95 * point[level - 1]);
  EXPECT_LT(std::abs(disc[8] - disc[7]), 0.01 * disc[8]);
  EXPECT_LT(std::abs(disc[8] - disc[7]) / disc[8], 0.25 * (point[7] - point[8]) / point[8]);
}

TEST(TissueStep, TorqueOfATiltedBarAndReferencePoint) {
  const TissueModel model = Model(6, MeshKind::kFine, SolverKind::kCholmod);
  ToolContact bar = G1Bar(kPress_m);
  const Result level = Step(model, bar);
  EXPECT_NEAR(level.tau.x(), 0.0, 1e-9);
  EXPECT_NEAR(level.tau.y(), 0.0, 1e-9);
  bar.p_ST.x() += 0.02;  // about a point 2 cm to the right: τ_y = −Σ r_x f = +0.02 F
  const Result shifted = Step(model, bar);
  EXPECT_NEAR(shifted.tau.y(), 0.02 * shifted.force_N, 1e-9);
  ToolContact tilted = MakeBarTool({0.05, 0.10, -0.5 * kPress_m}, {0.15, 0.10, -1.5 * kPress_m});
  const Result t = Step(model, tilted);
  EXPECT_LT(t.tau.y(), 0);  // the deeper right end pushes up harder: torque about −y
  EXPECT_EQ(t.tau.z(), 0.0);
}

// The tool sweeps at 1 m/s (more than a cell per step at level 7) while turning: contacts
// change every step, nothing fails, solvers agree step by step.
TEST(TissueStep, FastMovingToolNeverFails) {
  const TissueModel direct = Model(7, MeshKind::kMultiscale, SolverKind::kCholmod);
  for (SolverKind solver : {SolverKind::kPcgIc, SolverKind::kPcgDic}) {
    SCOPED_TRACE(ToString(solver));
    const TissueModel iterative = Model(7, MeshKind::kMultiscale, solver);
    TissueWorkspace ws_d(direct), ws_i(iterative);
    TissueState sd = MakeTissueState(direct), si = MakeTissueState(iterative);
    int twisted = 0, reattached = 0;
    for (int k = 0; k < 120; ++k) {
      const double t = 1e-3 * k, a = 3.0 * t;
      const double cx = 0.04 + 1.0 * t, cy = 0.1;
      const ToolContact bar =
          MakeBarTool({cx - 0.03 * std::cos(a), cy - 0.03 * std::sin(a), -kPress_m},
                      {cx + 0.03 * std::cos(a), cy + 0.03 * std::sin(a), -kPress_m});
      StepTissue(direct, bar, ws_d, sd);
      StepTissue(iterative, bar, ws_i, si);
      ASSERT_EQ(sd.status, TissueStatus::kOk) << k;
      ASSERT_EQ(si.status, TissueStatus::kOk) << k;
      ASSERT_TRUE(sd.f_T_S.allFinite() && sd.tau_T_S.allFinite());
      EXPECT_NEAR(si.f_T_S.z(), sd.f_T_S.z(), 1e-5 * sd.f_T_S.z()) << k;
      twisted += si.field_map.twist.turn_rad != 0;
      reattached += ws_i.stats.mesh_reattached;
      // pcg_dic keeps DIC on these systems (no fall-back to IC(0) needed).
      if (solver == SolverKind::kPcgDic) {
        EXPECT_EQ(ws_i.stats.preconditioner, Preconditioner::kDic) << k;
      }
    }
    // The attached mesh's twist (sheared, obtuse triangles) and its re-attachments are in play.
    EXPECT_GT(twisted, 60);
    EXPECT_GT(reattached, 0);
  }
}

TEST(TissueStep, FailuresKeepTheLastGoodState) {
  TissueDef def;
  def.max_level = 8;
  def.level = 6;
  def.solver = SolverKind::kCg;
  const TissueModel good_model = BuildTissueModel(def);
  def.cg_max_iterations = 2;
  const TissueModel starved = BuildTissueModel(def);
  TissueWorkspace ws(good_model);
  TissueState state = MakeTissueState(good_model);
  StepTissue(good_model, G1Bar(kPress_m), ws, state);
  ASSERT_EQ(state.status, TissueStatus::kOk);
  const TissueState good = state;
  TissueWorkspace ws_starved(starved);
  StepTissue(starved, G1Bar(2 * kPress_m), ws_starved, state);
  EXPECT_EQ(state.status, TissueStatus::kNotConverged);
  EXPECT_EQ(state.num_failed_steps, 1u);
  EXPECT_EQ(state.f_T_S, good.f_T_S);
  EXPECT_EQ(state.num_field_nodes, good.num_field_nodes);
  EXPECT_EQ(state.field_nodes, good.field_nodes);
  EXPECT_EQ(state.field_w_m, good.field_w_m);
  EXPECT_EQ(state.step, good.step);

  ToolContact bad = G1Bar(kPress_m);
  bad.p_SP[1].x() = std::numeric_limits<double>::quiet_NaN();
  StepTissue(good_model, bad, ws, state);
  EXPECT_EQ(state.status, TissueStatus::kBadInput);
  EXPECT_EQ(state.f_T_S, good.f_T_S);

  def.cg_max_iterations = 20000;
  def.max_contact_nodes = 4;
  const TissueModel small = BuildTissueModel(def);
  TissueWorkspace ws_small(small);
  TissueState s2 = MakeTissueState(small);
  StepTissue(small, G1Bar(kPress_m), ws_small, s2);
  EXPECT_EQ(s2.status, TissueStatus::kTooManyContacts);
  EXPECT_TRUE(s2.f_T_S.allFinite());
}

// With the nearest-node constraint the nodes under the bar hold U exactly.
TEST(TissueStep, DisplayFieldInterpolatesTheSolution) {
  const TissueModel model =
      Model(6, MeshKind::kMultiscale, SolverKind::kCholmod, 1e4, ToolConstraint::kNearestNodes);
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  StepTissue(model, G1Bar(kPress_m), ws, state);
  // Displayed on the model's finest grid, whose indices are the node ids.
  std::vector<double> grid, scratch;
  CalcDisplacementGrid(model, state, model.def.max_level, scratch, grid);
  const int side = model.nodes_per_side;
  ASSERT_EQ(grid.size(), static_cast<size_t>(model.num_grid_nodes));
  EXPECT_NEAR(grid[(side / 2) * side + side / 2], -kPress_m, 1e-15);  // under the bar
  EXPECT_EQ(grid[0], 0.0);                                            // fixed edge
  for (int k = 0; k < state.num_contacts; ++k) {
    const int node = state.contact_nodes[k];
    EXPECT_NEAR(grid[node], -kPress_m, 1e-15);
  }
  ASSERT_GT(state.num_field_nodes, 0);
  for (int k = 0; k < state.num_field_nodes; ++k) {
    EXPECT_NEAR(grid[state.field_nodes[k]], state.field_w_m[k], 1e-15);
  }
  for (int id = 0; id < model.num_grid_nodes; ++id) {
    EXPECT_LE(grid[id], 1e-15);  // maximum principle: nothing rises above the surface
    EXPECT_GE(grid[id], -kPress_m - 1e-15);
  }
}

TEST(TissueDef, ValidateNamesTheField) {
  TissueDef def;
  def.grading = 1.0;
  try {
    def.Validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("grading"), std::string::npos);
  }
  def = TissueDef{};
  def.level = def.max_level + 1;
  EXPECT_THROW(def.Validate(), std::invalid_argument);
  def = TissueDef{};
  def.shear_modulus_Pa = -1;
  EXPECT_THROW(BuildTissueModel(def), std::invalid_argument);
}

}  // namespace
}  // namespace microdex::fem

namespace microdex::fem {
namespace {

// The bar slid across one level-6 cell (off the grid lines at both ends of the slide) in 20
// and in 40 steps: the penalty-point force is continuous, so its largest change between
// steps halves with the step; the nearest nodes hold the force and then jump when the
// contact row changes, by the same amount however fine the steps.
// The mesh held to the grid (attached_mesh false): with the attached mesh the slide would not
// move the tool over the grid at all (attached_mesh_test.cc).
double LargestStepChange(ToolConstraint constraint, int steps) {
  TissueDef def = Model(6, MeshKind::kMultiscale, SolverKind::kPcgIc, 1e4, constraint).def;
  def.attached_mesh = false;
  const TissueModel model = BuildTissueModel(def);
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  const double h = model.CellSizeY_m(6);
  double previous = 0, largest = 0;
  for (int k = 0; k <= steps; ++k) {
    const double y = 0.1 + 0.013 * h + h * k / steps;
    StepTissue(model, MakeBarTool({0.0501, y, -kPress_m}, {0.1503, y, -kPress_m}), ws, state);
    EXPECT_EQ(state.status, TissueStatus::kOk);
    if (k > 0) largest = std::max(largest, std::abs(state.f_T_S.z() - previous));
    previous = state.f_T_S.z();
  }
  return largest / previous;
}

TEST(TissueStep, ForceIsContinuousUnderASubCellSlide) {
  const double points_20 = LargestStepChange(ToolConstraint::kPenaltyPoints, 20);
  const double points_40 = LargestStepChange(ToolConstraint::kPenaltyPoints, 40);
  const double nodes_20 = LargestStepChange(ToolConstraint::kNearestNodes, 20);
  const double nodes_40 = LargestStepChange(ToolConstraint::kNearestNodes, 40);
  EXPECT_LT(points_40, 0.6 * points_20);
  EXPECT_GT(nodes_40, 0.9 * nodes_20);
  EXPECT_LT(points_40, 2e-3);  // 2.5 % of a cell per step
}

// A tiny move of the tool changes the force by a tiny amount (same mesh): no snapping.
TEST(TissueStep, TinyMoveTinyForceChange) {
  const TissueModel model = Model(6, MeshKind::kMultiscale, SolverKind::kCholmod);
  const ToolContact a = MakeBarTool({0.0511, 0.1037, -kPress_m}, {0.1489, 0.1037, -kPress_m});
  ToolContact b = a;
  for (int k = 0; k < 2; ++k) b.p_SP[k] += Eigen::Vector3d(1e-7, 1e-7, 0);
  const double fa = Step(model, a).force_N, fb = Step(model, b).force_N;
  EXPECT_NE(fa, fb);                        // the force sees the move...
  EXPECT_LT(std::abs(fa - fb), 1e-5 * fa);  // ...in proportion
}

// A bar lifted out of the tissue at one end: the force falls to zero as it rises, without
// failures, and the step reports no contact once it is above the surface.
TEST(TissueStep, BarLiftedOutOfTheTissue) {
  const TissueModel model = Model(6, MeshKind::kMultiscale, SolverKind::kPcgIc);
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  double previous = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 20; ++k) {
    const double z_left = -kPress_m + 0.1 * kPress_m * k;  // rises to +1 cm
    StepTissue(model, MakeBarTool({0.05, 0.1031, z_left}, {0.15, 0.1031, -kPress_m + 0.0005 * k}),
               ws, state);
    ASSERT_TRUE(IsGood(state.status)) << k;
    ASSERT_TRUE(state.f_T_S.allFinite());
    EXPECT_LT(state.f_T_S.z(), previous) << k;
    previous = state.f_T_S.z();
  }
  EXPECT_EQ(state.status, TissueStatus::kNoContact);
  EXPECT_EQ(state.f_T_S.z(), 0.0);
}

// DIC exists for M-matrices; the tool points' springs (k λλᵀ, up to tool_penalty · G t) add
// positive off-diagonal entries. Over the whole range of tool_penalty and tool_kink_factor that
// TissueDef accepts, a bar moving and turning across the patch keeps DIC (no fall-back to
// IC(0)) and agrees with CHOLMOD step by step. With springs 1e8 G t the system's condition
// makes the residual test a loose bound on the force (IC(0)-PCG is 2 % off there, DIC 0.03 %).
TEST(TissueStep, DicPreconditionerHoldsOverThePenaltyRange) {
  for (double penalty : {1.0, 1e3, 1e8}) {
    for (double kink : {0.25, 1.2, 4.0}) {
      SCOPED_TRACE(testing::Message() << "tool_penalty " << penalty << " kink " << kink);
      TissueDef def;
      def.level = 5;
      def.max_level = 7;
      def.tool_penalty = penalty;
      def.tool_kink_factor = kink;
      def.solver = SolverKind::kPcgDic;
      const TissueModel dic = BuildTissueModel(def);
      def.solver = SolverKind::kCholmod;
      const TissueModel direct = BuildTissueModel(def);
      TissueWorkspace ws_dic(dic), ws_direct(direct);
      TissueState s_dic = MakeTissueState(dic), s_direct = MakeTissueState(direct);
      const double tol = penalty > 1e3 ? 1e-3 : 1e-5;
      for (int k = 0; k < 60; ++k) {
        const double t = 1e-3 * k, a = 3.0 * t;
        const double cx = 0.04 + 0.5 * t, cy = 0.1 + 4e-4 * k;
        const ToolContact bar =
            MakeBarTool({cx - 0.03 * std::cos(a), cy - 0.03 * std::sin(a), -kPress_m},
                        {cx + 0.03 * std::cos(a), cy + 0.03 * std::sin(a), -kPress_m});
        StepTissue(dic, bar, ws_dic, s_dic);
        StepTissue(direct, bar, ws_direct, s_direct);
        ASSERT_EQ(s_dic.status, TissueStatus::kOk) << k;
        ASSERT_EQ(ws_dic.stats.preconditioner, Preconditioner::kDic) << k;
        EXPECT_NEAR(s_dic.f_T_S.z(), s_direct.f_T_S.z(), tol * s_direct.f_T_S.z()) << k;
        EXPECT_LE(ws_dic.stats.relative_residual, 1.5 * def.cg_relative_tolerance) << k;
      }
    }
  }
}

}  // namespace
}  // namespace microdex::fem
