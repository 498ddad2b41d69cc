#include "common/fem/navier.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <random>
#include <string>

#include "common/fem/tissue_step.h"

namespace microdex::fem {
namespace {

constexpr double kPress_m = 0.01;

NavierDomain StudyDomain() { return NavierDomain{0.20, 0.20, 1e4, 0.01}; }

// The closed-form n-sum is the same series as (A.11) summed brute force.
TEST(Navier, ClosedFormInnerSumMatchesDoubleSeries) {
  const NavierDomain domain{0.20, 0.12, 2.5e3, 0.004};  // L ≠ B: catches L written for B
  const UniformLineLoad load{0.04, 0.13, 0.05, 3.0};
  for (const auto& [x, y] : {std::pair{0.07, 0.08}, std::pair{0.15, 0.02}, std::pair{0.1, 0.1}}) {
    int terms = 0;
    const double fast = NavierLineLoadDisplacement_m(domain, load, x, y, 1e-12, 1000000, &terms);
    const double brute = NavierDoubleSeries_m(domain, load, x, y, terms, 20000);
    EXPECT_NEAR(fast, brute, 1e-6 * std::abs(fast)) << x << "," << y;
    EXPECT_LT(terms, 2000);
  }
}

// Uniform load on the centred bar, G1 geometry: symmetric, and displacement positive for a
// positive load (the equation is G t ∇²w + p = 0 with p pushing +z).
TEST(Navier, LineLoadSymmetryAndSign) {
  const NavierDomain domain = StudyDomain();
  const UniformLineLoad load{0.05, 0.15, 0.10, 10.0};
  const double a = NavierLineLoadDisplacement_m(domain, load, 0.07, 0.13);
  const double b = NavierLineLoadDisplacement_m(domain, load, 0.13, 0.07);
  EXPECT_GT(a, 0);
  EXPECT_NEAR(a, b, 1e-12 * a);
}

TEST(Navier, BarHoldsThePrescribedDisplacement) {
  const NavierBar bar(StudyDomain(), 0.05, 0.15, 0.10, -kPress_m);
  for (double x = 0.0501; x < 0.15; x += 0.0099) {
    EXPECT_NEAR(bar.BarDisplacement_m(x), -kPress_m, 1e-9 * kPress_m) << x;
  }
  // The field just off the bar tends to the bar's displacement, and to 0 at the edges.
  EXPECT_NEAR(bar.Displacement_m(0.1, 0.1 + 1e-4), -kPress_m, 0.003 * kPress_m);
  EXPECT_NEAR(bar.Displacement_m(0.1, 0.1999), 0.0, 1e-3 * kPress_m);
  // Symmetric load, total = ∫ q.
  EXPECT_NEAR(bar.LoadDensity_N_per_m(0.07), bar.LoadDensity_N_per_m(0.13), 1e-9);
  EXPECT_NEAR(bar.IntervalForce_N(0.05, 0.15), bar.TotalForce_N(), 1e-12);
  double hats = 0;
  for (int i = 0; i <= 64; ++i) hats += bar.HatForce_N(0.05 + i * 0.1 / 64, 0.1 / 64);
  EXPECT_NEAR(hats, bar.TotalForce_N(), 1e-12);  // the hats are a partition of unity on the bar
}

TEST(Navier, ChebyshevExpansionConvergedAndRemainderSummed) {
  const NavierBar coarse(StudyDomain(), 0.05, 0.15, 0.025, -kPress_m, 16);
  const NavierBar fine(StudyDomain(), 0.05, 0.15, 0.025, -kPress_m, 48);
  EXPECT_NEAR(coarse.TotalForce_N(), fine.TotalForce_N(), 1e-10 * std::abs(fine.TotalForce_N()));
  EXPECT_GT(fine.remainder_terms(), 9);  // the bar near the edge needs more remainder terms
}

// The fine-mesh FEM converges to the Navier force of the pressed bar: the error falls by about
// two per level (the load is singular at the bar ends, so O(h)), and the Richardson
// extrapolation of two levels lands on the series value.
TEST(Navier, FineMeshFemConvergesToNavierForce) {
  const NavierBar bar(StudyDomain(), 0.05, 0.15, 0.10, -kPress_m);
  const double reference = -bar.TotalForce_N();  // force of the tissue on the tool, up
  double force[8] = {};
  for (int level = 4; level <= 7; ++level) {
    TissueDef def;
    def.max_level = level;
    def.level = level;
    def.mesh = MeshKind::kFine;
    def.solver = SolverKind::kCholmod;
    const TissueModel model = BuildTissueModel(def);
    TissueWorkspace ws(model);
    TissueState state = MakeTissueState(model);
    StepTissue(model, MakeBarTool({0.05, 0.1, -kPress_m}, {0.15, 0.1, -kPress_m}), ws, state);
    ASSERT_EQ(state.status, TissueStatus::kOk);
    force[level] = state.f_T_S.z();
  }
  for (int level = 5; level <= 7; ++level) {
    const double e0 = force[level - 1] - reference, e1 = force[level] - reference;
    EXPECT_GT(e0, e1);
    EXPECT_GT(e0 / e1, 1.7);
    EXPECT_LT(e0 / e1, 2.3);
  }
  EXPECT_NEAR(2 * force[7] - force[6], reference, 2e-3 * reference);
}

// The multi-scale mesh with end grading (ends at 10 cm / 64: level 7): the resultant force is
// within 2 % of the series from level 5 up, for the bar at the centre (G1) and near the
// border (G2). Without end grading
// the bar-end singularity keeps level 5 above 3 % (the fine mesh itself is 3.2 % off there).
TEST(Navier, EndGradedMultiscaleForceWithinTwoPercent) {
  constexpr double kForceTol = 0.02;  // relative, the goal
  for (const double y_bar : {0.10, 0.025}) {
    const NavierBar bar(StudyDomain(), 0.05, 0.15, y_bar, -kPress_m, 24);
    const double reference = -bar.TotalForce_N();
    for (const double end_resolution : {0.0, 64.0}) {
      for (int level = 5; level <= 6; ++level) {
        TissueDef def;
        def.level = level;
        def.end_resolution = end_resolution;
        def.max_level = level + 2;
        def.mesh = MeshKind::kMultiscale;
        def.solver = SolverKind::kCholmod;
        const TissueModel model = BuildTissueModel(def);
        TissueWorkspace ws(model);
        TissueState state = MakeTissueState(model);
        StepTissue(model, MakeBarTool({0.05, y_bar, -kPress_m}, {0.15, y_bar, -kPress_m}), ws,
                   state);
        ASSERT_EQ(state.status, TissueStatus::kOk);
        const double error = (state.f_T_S.z() - reference) / reference;
        EXPECT_GT(error, 0);  // a conforming subspace: the discrete system is stiffer
        if (end_resolution > 0) {
          EXPECT_LT(error, kForceTol) << "y " << y_bar << " level " << level;
        } else if (level == 5) {
          EXPECT_GT(error, 0.03) << "y " << y_bar;
        }
      }
    }
  }
}

}  // namespace
}  // namespace microdex::fem

namespace microdex::fem {
namespace {

// The resultant of one cold step (cholmod) on the multi-scale mesh (max_level two above) or the
// fine mesh of `level`.
double ForceOnMesh_N(MeshKind mesh, int level, ToolConstraint constraint, const ToolContact& tool) {
  TissueDef def;
  def.mesh = mesh;
  def.max_level = mesh == MeshKind::kFine ? level : level + 2;
  def.level = level;
  def.solver = SolverKind::kCholmod;
  def.tool_constraint = constraint;
  const TissueModel model = BuildTissueModel(def);
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  StepTissue(model, tool, ws, state);
  EXPECT_EQ(state.status, TissueStatus::kOk);
  return state.f_T_S.z();
}

double MultiscaleForce_N(int level, ToolConstraint constraint, const ToolContact& tool) {
  return ForceOnMesh_N(MeshKind::kMultiscale, level, constraint, tool);
}

double FineForce_N(int level, ToolConstraint constraint, const ToolContact& tool) {
  return ForceOnMesh_N(MeshKind::kFine, level, constraint, tool);
}

// A reference for tools that are not axis-aligned bars, from fine uniform meshes that conform
// to the tool: it runs along the cells' edges (grid lines and the lower-left to upper-right
// diagonals, corners and ends on nodes of level 6) and its displacement is imposed on the nodes
// under it. The Richardson value 2 F₈ − F₇ (the force error is O(h)) is the reference; its
// change against 2 F₇ − F₆ bounds its own error. On G1 it is checked against Navier; for a 45°
// bar and a polyline (45°, then along x) the multi-scale penalty-point resultant is within 2 %
// of it at levels 5–7.
TEST(Navier, ConformingFineReferenceForTiltedToolsAndTheTwoPercentAtLevelsFromFive) {
  struct Case {
    const char* name;
    ToolContact tool;
  };
  const std::array<Eigen::Vector3d, 3> zed = {Eigen::Vector3d(0.05, 0.0625, -kPress_m),
                                              Eigen::Vector3d(0.10, 0.1125, -kPress_m),
                                              Eigen::Vector3d(0.15, 0.1125, -kPress_m)};
  const Case cases[] = {
      {"G1", MakeBarTool({0.05, 0.10, -kPress_m}, {0.15, 0.10, -kPress_m})},
      {"D45", MakeBarTool({0.05, 0.05, -kPress_m}, {0.125, 0.125, -kPress_m})},
      {"Z", MakePolylineTool(zed, 0.0)},
  };
  for (const Case& c : cases) {
    double f[3];
    for (int k = 0; k < 3; ++k) f[k] = FineForce_N(6 + k, ToolConstraint::kNearestNodes, c.tool);
    const double reference = 2 * f[2] - f[1];
    const double estimate = std::abs(reference - (2 * f[1] - f[0])) / reference;
    EXPECT_LT(estimate, 2e-3) << c.name;
    if (std::string(c.name) == "G1") {
      const double navier =
          -NavierBar(StudyDomain(), 0.05, 0.15, 0.10, -kPress_m, 40).TotalForce_N();
      EXPECT_NEAR(reference, navier, 2e-3 * navier) << "the conforming reference against Navier";
    }
    for (int level = 5; level <= 7; ++level) {
      const double ms = MultiscaleForce_N(level, ToolConstraint::kPenaltyPoints, c.tool);
      EXPECT_NEAR(ms, reference, 0.02 * reference) << c.name << " at level " << level;
    }
  }
}

// Bars at seeded random positions (2–14 cm long, ends and line anywhere at least 2 mm from the
// edges, so neither on grid lines nor grid nodes): the penalty-point resultant is within 2 % of
// Navier at levels 5–7; the nearest-node constraint (the tool snapped to the grid) is not.
TEST(Navier, OffGridBarsWithinTwoPercentAtEveryLevelFromFive) {
  constexpr double kMargin_m = 0.002;
  constexpr int kBars = 6;
  std::mt19937_64 rng(20261125);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst_nodes = 0;
  for (int c = 0; c < kBars; ++c) {
    const double length = 0.02 + 0.12 * unit(rng);
    const double x1 = kMargin_m + (0.20 - 2 * kMargin_m - length) * unit(rng);
    const double y1 = kMargin_m + (0.20 - 2 * kMargin_m) * unit(rng);
    const double x2 = x1 + length;
    const double reference = -NavierBar(StudyDomain(), x1, x2, y1, -kPress_m, 40).TotalForce_N();
    const ToolContact bar = MakeBarTool({x1, y1, -kPress_m}, {x2, y1, -kPress_m});
    for (int level = 5; level <= 7; ++level) {
      const double f = MultiscaleForce_N(level, ToolConstraint::kPenaltyPoints, bar);
      EXPECT_NEAR(f, reference, 0.02 * reference)
          << "bar " << x1 << "–" << x2 << " at y " << y1 << ", level " << level;
      const double nodes = MultiscaleForce_N(level, ToolConstraint::kNearestNodes, bar);
      worst_nodes = std::max(worst_nodes, std::abs(nodes - reference) / reference);
    }
  }
  EXPECT_GT(worst_nodes, 0.02);  // the positions do test what snapping gets wrong
}

// Bars with their line or an end 2–6 mm from a clamped edge (seeded random positions), on
// the model a station builds (max_level 9): within 2 % of Navier at levels 5–8 with edge
// grading. Without it the strip between the bar and the edge, where w falls from U to 0, is
// thinner than the cells that hold it (8 % at level 5 for a bar 2 mm from the edge).
TEST(Navier, BarsNearAnEdgeWithinTwoPercentAtEveryLevelFromFive) {
  constexpr int kBars = 6;
  std::mt19937_64 rng(20261126);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst_without = 0;
  for (int c = 0; c < kBars; ++c) {
    const double length = 0.02 + 0.12 * unit(rng);
    double x1 = 0, y = 0;
    if (c % 2 == 0) {  // the line near the bottom or top edge
      x1 = 0.002 + (0.196 - length) * unit(rng);
      y = 0.002 + 0.004 * unit(rng);
      if (unit(rng) < 0.5) y = 0.20 - y;
    } else {  // an end near the left edge
      x1 = 0.002 + 0.004 * unit(rng);
      y = 0.002 + 0.196 * unit(rng);
    }
    const double x2 = std::min(x1 + length, 0.198);
    const double reference = -NavierBar(StudyDomain(), x1, x2, y, -kPress_m, 40).TotalForce_N();
    const ToolContact bar = MakeBarTool({x1, y, -kPress_m}, {x2, y, -kPress_m});
    for (int level = 5; level <= 8; ++level) {
      for (const double edge_resolution : {TissueDef{}.edge_resolution, 0.0}) {
        TissueDef def;
        def.max_level = std::max(9, level + 1);
        def.level = level;
        def.solver = SolverKind::kCholmod;
        def.edge_resolution = edge_resolution;
        const TissueModel model = BuildTissueModel(def);
        TissueWorkspace ws(model);
        TissueState state = MakeTissueState(model);
        StepTissue(model, bar, ws, state);
        ASSERT_EQ(state.status, TissueStatus::kOk);
        const double error = std::abs(state.f_T_S.z() - reference) / reference;
        if (edge_resolution > 0) {
          EXPECT_LT(error, 0.02) << "bar " << x1 << "–" << x2 << " at y " << y << ", level "
                                 << level;
        } else {
          worst_without = std::max(worst_without, error);
        }
      }
    }
  }
  EXPECT_GT(worst_without, 0.04);  // the positions do test the strip by the edge
}

// On grid lines, with ends on nodes (the study's bars), the penalty points give the answer of
// the nearest-node constraint.
TEST(Navier, GridAlignedBarsAgreeWithTheNearestNodeConstraint) {
  for (const double y : {0.10, 0.025}) {
    const ToolContact bar = MakeBarTool({0.05, y, -kPress_m}, {0.15, y, -kPress_m});
    const double reference = -NavierBar(StudyDomain(), 0.05, 0.15, y, -kPress_m, 40).TotalForce_N();
    for (int level = 5; level <= 6; ++level) {
      const double points = MultiscaleForce_N(level, ToolConstraint::kPenaltyPoints, bar);
      const double nodes = MultiscaleForce_N(level, ToolConstraint::kNearestNodes, bar);
      EXPECT_NEAR(points, nodes, 0.005 * nodes) << "y " << y << " level " << level;
      EXPECT_NEAR(points, reference, 0.02 * reference) << "y " << y << " level " << level;
    }
  }
}

}  // namespace
}  // namespace microdex::fem
