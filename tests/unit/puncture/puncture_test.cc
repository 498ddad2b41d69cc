// Needle puncture (common/puncture): the analytic nearest point and crossings against brute
// force, the puncture at the material threshold, a pass along the needle's own circle that
// tears nothing, tearing and friction laws, withdrawal, and sweeps over stiff and extreme
// parameters.

#include "common/puncture/puncture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/fem/tissue_model.h"
#include "tests/support/alloc_counter.h"
#include "tests/unit/puncture/puncture_scenarios.h"

namespace microdex::puncture {
namespace {

using testing::ThroughScenario;

NeedleArc RandomArc(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
  NeedleArc arc;
  arc.e1_S = a.normalized();
  arc.e2_S = (b - b.dot(arc.e1_S) * arc.e1_S).normalized();
  arc.c_S = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 5e-3;
  arc.radius_m = 1e-3 * (1.0 + 4.0 * (u(rng) + 1));
  arc.sweep_rad = 0.2 + (u(rng) + 1) * 2.9;
  return arc;
}

TEST(ClosestArcParameter, MatchesDenseSampling) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  constexpr int kSamples = 200000;
  for (int c = 0; c < 200; ++c) {
    const NeedleArc arc = RandomArc(rng);
    const Eigen::Vector3d q = arc.c_S + Eigen::Vector3d(u(rng), u(rng), u(rng)) * 8e-3;
    double d_exact = 0;
    const double s = ClosestArcParameter(arc, q, &d_exact);
    ASSERT_GE(s, 0.0);
    ASSERT_LE(s, arc.sweep_rad);
    double d_brute = 1e300;
    for (int i = 0; i <= kSamples; ++i) {
      d_brute = std::min(d_brute, (q - arc.Point(arc.sweep_rad * i / kSamples)).norm());
    }
    // The sampled minimum is never below the exact one, and above it by at most the chord
    // error of the sampling.
    const double ds = arc.sweep_rad / kSamples;
    EXPECT_LE(d_exact, d_brute + 1e-15) << "case " << c;
    EXPECT_LE(d_brute - d_exact, arc.radius_m * ds) << "case " << c;
  }
}

TEST(RestPlaneCrossings, AreZerosOfTheHeightAndAsManyAsTheSignChanges) {
  std::mt19937_64 rng(11);
  int seen[3] = {0, 0, 0};
  for (int c = 0; c < 2000; ++c) {
    const NeedleArc arc = RandomArc(rng);
    std::array<double, 2> s{};
    const int n = RestPlaneCrossings(arc, s);
    ++seen[n];
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(arc.Point(s[i]).z(), 0.0, 1e-15) << "case " << c;
      EXPECT_GE(s[i], 0.0);
      EXPECT_LE(s[i], arc.sweep_rad);
    }
    if (n == 2) {
      EXPECT_LT(s[0], s[1]);
    }
    int changes = 0;
    constexpr int kSamples = 20000;
    for (int i = 0; i < kSamples; ++i) {
      const double z0 = arc.Point(arc.sweep_rad * i / kSamples).z();
      const double z1 = arc.Point(arc.sweep_rad * (i + 1) / kSamples).z();
      changes += (z0 < 0) != (z1 < 0);
    }
    EXPECT_EQ(changes, n) << "case " << c;
  }
  // The random arcs cover all three cases.
  EXPECT_GT(seen[0], 0);
  EXPECT_GT(seen[1], 0);
  EXPECT_GT(seen[2], 0);
}

// Turns the scenario's needle from its tip just above the entry to `a_end`, `steps` steps;
// records the largest pressing force before the first puncture and the force just after it.
struct Pass {
  PunctureState state;
  double peak_force_before_N = 0;
  double force_after_N = -1;
  int puncture_step = -1;
  double max_force_N = 0;
};

Pass TurnThrough(const ThroughScenario& sc, const fem::TissueModel& model, double a_start,
                 double a_end, int steps) {
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  Pass pass;
  for (int k = 0; k <= steps; ++k) {
    const double a = a_start + (a_end - a_start) * k / steps;
    StepPuncture(sc.def, model, sc.ArcWithTipAt(a), ws, tissue, pass.state);
    const double f = pass.state.f_S.norm();
    pass.max_force_N = std::max(pass.max_force_N, f);
    if (pass.puncture_step < 0) {
      if (pass.state.punctures > 0) {
        pass.puncture_step = k;
        pass.force_after_N = f;
      } else {
        pass.peak_force_before_N = std::max(pass.peak_force_before_N, f);
      }
    }
  }
  return pass;
}

TEST(StepPuncture, AlongItsOwnCircleTheNeedlePiercesTwiceAndTearsNothing) {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  // 5 mm/s at the tip, 1 kHz.
  const double a0 = sc.EntryAngle() - 0.05, a1 = sc.ExitAngle() + 0.4;
  const int steps = static_cast<int>((a1 - a0) * sc.radius_m / 5e-6);
  const Pass pass = TurnThrough(sc, model, a0, a1, steps);
  const PunctureState& st = pass.state;
  ASSERT_EQ(st.punctures, 2);
  ASSERT_EQ(st.have_entry, 1);
  ASSERT_EQ(st.have_exit, 1);
  EXPECT_EQ(CountOpenHoles(st), 2);  // the needle spans both holes; its tip is above
  // The membrane pushed back, harder as the tip went deeper, and gave way at the threshold.
  EXPECT_GE(pass.peak_force_before_N, 0.9 * sc.def.puncture_force_N);
  EXPECT_LT(pass.peak_force_before_N, sc.def.puncture_force_N);
  EXPECT_GE(st.peak_press_N, sc.def.puncture_force_N);
  EXPECT_LT(pass.force_after_N, 0.5 * sc.def.puncture_force_N);  // the pop
  // The holes sit where the circle crosses the rest plane.
  const Eigen::Vector3d entry = sc.ArcWithTipAt(sc.EntryAngle()).Point(sc.sweep_rad);
  const Eigen::Vector3d exit = sc.ArcWithTipAt(sc.ExitAngle()).Point(sc.sweep_rad);
  EXPECT_LT((st.p_S_entry - entry).norm(), 1e-12);
  EXPECT_LT((st.p_S_exit - exit).norm(), 1e-12);
  // Nothing moved across the holes: no strain, no tear, no off-circle motion.
  EXPECT_LT(st.peak_strain, 1e-9);
  EXPECT_EQ(st.torn_m, 0.0);
  EXPECT_LT(st.off_circle_m, 1e-12);
  // What the holes do is friction along the needle, at its sliding limit μ · grip.
  for (int i = 0; i < st.num_holes; ++i) {
    const Hole& h = st.holes[i];
    const Eigen::Vector3d t = sc.ArcWithTipAt(a1).Tangent(h.s_rad);
    EXPECT_NEAR(h.f_S.dot(t), -sc.def.friction_coefficient * sc.def.grip_force_N, 1e-12);
    EXPECT_LT((h.f_S - h.f_S.dot(t) * t).norm(), 1e-9);
  }
}

TEST(StepPuncture, ThePunctureForceFollowsTheMaterialThreshold) {
  ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  const double a0 = sc.EntryAngle() - 0.05, a1 = sc.EntryAngle() + 0.7;
  double prev_depth = 0;
  for (const double threshold : {0.01, 0.02, 0.03}) {
    sc.def.puncture_force_N = threshold;
    const Pass pass = TurnThrough(sc, model, a0, a1, 2000);
    ASSERT_EQ(pass.state.punctures, 1) << threshold;
    EXPECT_GE(pass.state.peak_press_N, threshold);
    EXPECT_LT(pass.peak_force_before_N, threshold);
    // The membrane is linear: the depth at puncture (threshold / stiffness) grows with it.
    const double depth = threshold / pass.state.holes[0].normal_stiffness_N_per_m;
    EXPECT_GT(depth, prev_depth);
    prev_depth = depth;
  }
}

// Through the entry, then a sideways shift of the needle out of its plane.
TEST(StepPuncture, MovingAcrossAHoleStrainsItThenTearsIt) {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  PunctureState st;
  const double a_in = sc.EntryAngle() + 0.4;
  for (int k = 0; k <= 500; ++k) {
    const double a = sc.EntryAngle() - 0.05 + (0.45 * k) / 500;
    StepPuncture(sc.def, model, sc.ArcWithTipAt(a), ws, tissue, st);
  }
  ASSERT_EQ(CountOpenHoles(st), 1);
  const double limit_m = sc.def.tear_strain * sc.def.wire_radius_m;
  const double shift_m = 1e-3;
  double prev_strain = 0;
  for (int k = 1; k <= 1000; ++k) {
    NeedleArc arc = sc.ArcWithTipAt(a_in);
    arc.c_S.y() += shift_m * k / 1000;
    StepPuncture(sc.def, model, arc, ws, tissue, st);
    const Hole& h = st.holes[0];
    EXPECT_GE(h.strain, prev_strain - 1e-12);  // strain grows until it tears, then stays
    EXPECT_LE(h.strain, sc.def.tear_strain * (1 + 1e-12));
    prev_strain = h.strain;
  }
  EXPECT_NEAR(st.peak_strain, sc.def.tear_strain, 1e-9);
  EXPECT_NEAR(st.torn_m, shift_m - limit_m, 1e-9);
  EXPECT_NEAR(st.off_circle_m, shift_m, 1e-9);
  // The hole pulls the needle back (−y) with the tear force.
  const Hole& h = st.holes[0];
  EXPECT_NEAR(h.f_S.y(), -sc.def.lateral_stiffness_N_per_m * limit_m, 1e-9);
}

TEST(StepPuncture, FrictionOpposesTheSlidingAndIsBoundedByCoulomb) {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  PunctureState st;
  double a = sc.EntryAngle() - 0.05;
  for (; a < sc.EntryAngle() + 0.4; a += 1e-3) {
    StepPuncture(sc.def, model, sc.ArcWithTipAt(a), ws, tissue, st);
  }
  ASSERT_EQ(CountOpenHoles(st), 1);
  const double limit_N = sc.def.friction_coefficient * sc.def.grip_force_N;
  // Back and forth: the force along the tangent opposes the motion once the bristle slips,
  // and never exceeds the Coulomb limit.
  for (const double dir : {-1.0, 1.0, -1.0}) {
    for (int k = 0; k < 200; ++k) {
      a += dir * 2e-4;
      const NeedleArc arc = sc.ArcWithTipAt(a);
      StepPuncture(sc.def, model, arc, ws, tissue, st);
      const Hole& h = st.holes[0];
      const double f_t = h.f_S.dot(arc.Tangent(h.s_rad));
      EXPECT_LE(std::abs(f_t), limit_N * (1 + 1e-12));
      if (k > 20) {
        EXPECT_NEAR(f_t, -dir * limit_N, 1e-12) << "dir " << dir << " step " << k;
      }
    }
  }
}

TEST(StepPuncture, DrawingTheNeedleBackLeavesTheHoleAndTheTipAbove) {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  const double in = sc.EntryAngle() + 0.45;
  Pass pass = TurnThrough(sc, model, sc.EntryAngle() - 0.05, in, 400);
  ASSERT_EQ(CountOpenHoles(pass.state), 1);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  for (int k = 0; k <= 400; ++k) {
    const double a = in - 0.55 * k / 400;
    StepPuncture(sc.def, model, sc.ArcWithTipAt(a), ws, tissue, pass.state);
  }
  EXPECT_EQ(CountOpenHoles(pass.state), 0);
  EXPECT_EQ(pass.state.holes[0].status, HoleStatus::kLeftByTip);
  EXPECT_EQ(pass.state.f_S.norm(), 0.0);
  EXPECT_EQ(pass.state.punctures, 1);
}

TEST(StepPuncture, ANonFiniteNeedleIsSkippedAndCounted) {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  PunctureState st;
  NeedleArc arc = sc.ArcWithTipAt(sc.EntryAngle());
  arc.c_S.x() = std::numeric_limits<double>::quiet_NaN();
  StepPuncture(sc.def, model, arc, ws, tissue, st);
  EXPECT_EQ(st.warnings, 1u);
  EXPECT_EQ(st.f_S, Eigen::Vector3d::Zero());
  EXPECT_EQ(st.have_prev, 0);
}

// Random wandering motions (turns about the needle's axis and shakes of its pose) at the
// extremes of every parameter: forces stay finite, each hole within its laws.
TEST(StepPuncture, StiffAndExtremeParametersStayBoundedAndFinite) {
  ThroughScenario base;
  struct Case {
    double threshold, lateral, tear, bristle, mu, modulus;
  };
  const Case cases[] = {
      {1e-5, 200, 1, 2000, 0.3, 2e4},    {10, 200, 1, 2000, 0.3, 2e4},
      {0.03, 0, 1, 2000, 0.3, 2e4},      {0.03, 1e6, 1, 2000, 0.3, 2e4},
      {0.03, 200, 1e-3, 2000, 0.3, 2e4}, {0.03, 200, 100, 2000, 0.3, 2e4},
      {0.03, 200, 1, 1, 0.3, 2e4},       {0.03, 200, 1, 1e8, 2.0, 2e4},
      {0.03, 200, 1, 2000, 0, 2e4},      {1e-10, 200, 1, 2000, 0.3, 1e-3},
      {0.03, 200, 1, 2000, 0.3, 1e9},
  };
  int punctured_cases = 0;
  for (const Case& c : cases) {
    ThroughScenario sc = base;
    sc.def.puncture_force_N = c.threshold;
    sc.def.lateral_stiffness_N_per_m = c.lateral;
    sc.def.tear_strain = c.tear;
    sc.def.bristle_stiffness_N_per_m = c.bristle;
    sc.def.friction_coefficient = c.mu;
    sc.tissue.shear_modulus_Pa = c.modulus;
    ASSERT_NO_THROW(sc.def.Validate());
    const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
    fem::TissueWorkspace ws(model);
    fem::TissueState tissue = fem::MakeTissueState(model);
    PunctureState st;
    std::mt19937_64 rng(3);
    std::normal_distribution<double> n(0, 1);
    double a = sc.EntryAngle() - 0.05;
    Eigen::Vector3d shake = Eigen::Vector3d::Zero();
    for (int k = 0; k < 1500; ++k) {
      a += 1.2e-3 + 2e-3 * n(rng);
      shake += 20e-6 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      NeedleArc arc = sc.ArcWithTipAt(a);
      arc.c_S += shake;
      StepPuncture(sc.def, model, arc, ws, tissue, st);
      ASSERT_TRUE(st.f_S.allFinite()) << "threshold " << c.threshold << " step " << k;
      const double limit_m = sc.def.tear_strain * sc.def.wire_radius_m;
      for (int i = 0; i < st.num_holes; ++i) {
        const Hole& h = st.holes[i];
        if (h.status != HoleStatus::kOpen) continue;
        ASSERT_LE(h.strain, sc.def.tear_strain * (1 + 1e-9));
        const Eigen::Vector3d f_hold = h.f_S - h.friction_N * arc.Tangent(h.s_rad);
        ASSERT_LE(std::abs(h.friction_N), sc.def.friction_coefficient *
                                              (sc.def.grip_force_N + f_hold.norm()) * (1 + 1e-12));
        ASSERT_LE(std::hypot(f_hold.x(), f_hold.y()),
                  sc.def.lateral_stiffness_N_per_m * limit_m * (1 + 1e-9));
      }
      ASSERT_LT(st.press_N, sc.def.puncture_force_N);
    }
    punctured_cases += st.punctures > 0;
    EXPECT_EQ(st.punctures > 0, c.threshold < 1)
        << "threshold " << c.threshold << " G " << c.modulus;
  }
  // Every case but the 10 N threshold pierces.
  EXPECT_EQ(punctured_cases, static_cast<int>(std::size(cases)) - 1);
}

TEST(StepPuncture, StepsWithoutAllocatingAfterWarmUp) {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  PunctureState st;
  const double a0 = sc.EntryAngle() - 0.05, a1 = sc.ExitAngle() + 0.3;
  constexpr int kSteps = 1500;
  // Warm up on the same pass (the FEM's pattern cache and CG buffers), then count.
  for (int k = 0; k <= kSteps; ++k) {
    StepPuncture(sc.def, model, sc.ArcWithTipAt(a0 + (a1 - a0) * k / kSteps), ws, tissue, st);
  }
  st = PunctureState{};
  tissue = fem::MakeTissueState(model);
  microdex::testing::StartCountingAllocations();
  for (int k = 0; k <= kSteps; ++k) {
    StepPuncture(sc.def, model, sc.ArcWithTipAt(a0 + (a1 - a0) * k / kSteps), ws, tissue, st);
  }
  EXPECT_EQ(microdex::testing::StopCountingAllocations(), 0u);
  EXPECT_EQ(st.punctures, 2);
}

TEST(PunctureDef, RejectsBadFieldsByName) {
  const auto message = [](PunctureDef def) {
    try {
      def.Validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  PunctureDef d;
  d.puncture_force_N = 0;
  EXPECT_EQ(message(d).rfind("puncture_force_N: ", 0), 0u);
  d = PunctureDef{};
  d.wire_radius_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message(d).rfind("wire_radius_m: ", 0), 0u);
  d = PunctureDef{};
  d.friction_coefficient = -0.1;
  EXPECT_EQ(message(d).rfind("friction_coefficient: ", 0), 0u);
  d = PunctureDef{};
  d.tear_strain = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message(d).rfind("tear_strain: ", 0), 0u);
  EXPECT_EQ(message(PunctureDef{}), "");
}

}  // namespace
}  // namespace microdex::puncture
