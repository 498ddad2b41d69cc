// The grasp step against independent references: rest on the table, the free-fall parabola,
// Coulomb's sticking and sliding on an incline (a = g (sin θ - μ cos θ)), the hold threshold
// m g / (2 μ) of a two-jaw grasp, the sense of rotation of misaligned grasps from the torque of
// gravity and of the jaws, and the real-time contract (no allocation, bit-exact copies, finite
// state after bad input).
#include "common/grasp/grasp_step.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "common/grasp/grasp_metrics.h"
#include "tests/support/alloc_counter.h"
#include "tests/unit/grasp/grasp_scenarios.h"

namespace microdex::grasp {
namespace {

using testing::FarTool;
using testing::MilligramCubeDef;

constexpr double kPi = std::numbers::pi;
// Rotation of a grasp that should not turn the object: the residual of the contact solver at
// its default 20 iterations (measured 2.3e-4 rad for the aligned lift, falling with more
// iterations: microdex-bench grasp); a misaligned grasp turns it by more than 5°.
constexpr double kAlignedRotationTol_rad = 2e-3;
// Creep of a sticking contact over half a second: the solver's residual slip (measured 5 nm);
// a sliding box travels centimetres in that time.
constexpr double kStickCreep_m = 20e-9;

GraspDef ShapeDefOf(ShapeKind kind, double density) {
  GraspDef def = MilligramCubeDef();
  def.shape.kind = kind;
  def.shape.radius_m = 0.5e-3;
  def.shape.length_m = 1e-3;
  def.density_kg_per_m3 = density;
  def.contact.jaw_stiffness_N_per_m = 1e4;
  return def;
}

// ---- rest and free fall ----------------------------------------------------------------------

// Ten seconds at rest: 10 nm of creep (1e-5 of the millimetre object) and 1e-5 rad, the contact
// solver's residual (measured 1.5 nm and 2e-6 rad for the cylinder on its cap).
constexpr double kRestDrift_m = 10e-9;
constexpr double kRestTurn_rad = 1e-5;

class GraspRestTest : public ::testing::TestWithParam<std::tuple<ShapeKind, double>> {};

TEST_P(GraspRestTest, StaysPutForTenSeconds) {
  const auto [kind, density] = GetParam();
  const GraspModel model = MakeGraspModel(ShapeDefOf(kind, density));
  GraspState state = MakeGraspStateOnTable(model, Eigen::Vector3d(1e-3, -2e-3, 0.0));
  const GraspState start = state;
  GraspWorkspace w;
  const GraspInput in = FarTool();
  // The resting spring's sag: m g / k with the table's stiffness (four points share it), or,
  // where the step's stiffness limit binds, g h^2 / table_stiffness_limit (ContactDef).
  const double h = FarTool().dt_s;
  const double sag_m = std::max(4.0 * model.weight_N / model.def.contact.table_stiffness_N_per_m,
                                9.81 * h * h / model.def.contact.table_stiffness_limit);
  double max_speed = 0.0, max_spin = 0.0;
  for (int k = 0; k < 10000; ++k) {
    StepGrasp(model, in, w, state);
    if (k >= 100) {
      max_speed = std::max(max_speed, state.v_WO.norm());
      max_spin = std::max(max_spin, state.w_WO.norm());
    }
  }
  const Eigen::Vector3d drift = state.X_WO.p_W - start.X_WO.p_W;
  EXPECT_LT(drift.head<2>().norm(), kRestDrift_m) << "horizontal drift, m";
  EXPECT_LT(std::abs(drift.z()), 1.01 * sag_m + 1e-12) << "sinking, m";
  EXPECT_LT(CalcRotationAngle(start.X_WO.q(), state.X_WO.q()), kRestTurn_rad);
  EXPECT_LT(max_speed, 1e-7) << "jitter, m/s";
  EXPECT_LT(max_spin, 1e-4) << "jitter, rad/s";
  EXPECT_EQ(state.warnings, GraspWarnings{});
}

INSTANTIATE_TEST_SUITE_P(GraspShapes, GraspRestTest,
                         ::testing::Combine(::testing::Values(ShapeKind::kBox, ShapeKind::kCylinder,
                                                              ShapeKind::kSphere),
                                            ::testing::Values(1000.0, 8000.0)));

TEST(GraspFreeFall, FollowsTheParabolaAndKeepsItsSpin) {
  GraspDef def = ShapeDefOf(ShapeKind::kBox, 1000.0);
  def.shape.box_size_m = Eigen::Vector3d(1e-3, 2e-3, 0.5e-3);
  const GraspModel model = MakeGraspModel(def);
  GraspState state;
  state.X_WO.p_W = Eigen::Vector3d(0.0, 0.0, 0.05);
  state.v_WO = Eigen::Vector3d(0.01, -0.02, 0.1);
  state.w_WO = Eigen::Vector3d(0.0, 0.0, 30.0);  // about a principal axis: steady
  const GraspState start = state;
  GraspWorkspace w;
  const GraspInput in = FarTool();
  const double g = 9.81, h = in.dt_s;
  for (int k = 1; k <= 100; ++k) {
    StepGrasp(model, in, w, state);
    const double t = k * h;
    const Eigen::Vector3d exact =
        start.X_WO.p_W + t * start.v_WO + 0.5 * t * t * def.gravity_m_per_s2;
    // Symplectic Euler lags the parabola by exactly g h t / 2 in height.
    EXPECT_NEAR(state.X_WO.p_W.x(), exact.x(), 1e-12);
    EXPECT_NEAR(state.X_WO.p_W.y(), exact.y(), 1e-12);
    EXPECT_LE(std::abs(state.X_WO.p_W.z() - exact.z()), 0.5 * g * h * t * (1.0 + 1e-9) + 1e-12);
  }
  EXPECT_NEAR(state.w_WO.z(), 30.0, 1e-9);
  EXPECT_NEAR(CalcRotationAngle(start.X_WO.q(), state.X_WO.q()), 30.0 * 0.1, 1e-9);
}

TEST(GraspFreeFall, TumblingBodyGainsNoEnergy) {
  GraspDef def = ShapeDefOf(ShapeKind::kBox, 1000.0);
  def.shape.box_size_m = Eigen::Vector3d(0.5e-3, 1e-3, 2e-3);
  def.gravity_m_per_s2.setZero();
  const GraspModel model = MakeGraspModel(def);
  GraspState state;
  state.X_WO.p_W = Eigen::Vector3d(0.0, 0.0, 1.0);
  state.w_WO = Eigen::Vector3d(20.0, 1.0, 0.5);  // near the intermediate axis: it tumbles
  auto energy = [&](const GraspState& s) {
    const Eigen::Matrix3d R = s.X_WO.q().toRotationMatrix();
    const Eigen::Vector3d w_B = R.transpose() * s.w_WO;
    return 0.5 * w_B.dot(model.inertia_kg_m2.cwiseProduct(w_B));
  };
  const double e0 = energy(state);
  GraspWorkspace w;
  for (int k = 0; k < 5000; ++k) {
    StepGrasp(model, FarTool(), w, state);
    ASSERT_LE(energy(state), e0 * (1.0 + 1e-12));
  }
  EXPECT_GT(energy(state), 0.5 * e0) << "the implicit gyroscopic term damps, but slowly";
}

// ---- Coulomb on an incline -------------------------------------------------------------------

TEST(GraspIncline, SticksBelowTheFrictionAngle) {
  for (double mu : {0.3, 0.5, 1.0}) {
    GraspDef def = MilligramCubeDef();
    def.shape.box_size_m.z() = 0.25e-3;  // flat: it does not tip below tan(theta) = 4
    def.table_friction = mu;
    const double theta = 0.9 * std::atan(mu);
    const testing::InclineResult r = testing::RunIncline(def, theta, 0.5, 1.0);
    EXPECT_TRUE(r.finite);
    EXPECT_LT(std::abs(r.displacement_m), kStickCreep_m) << "mu " << mu;
  }
}

TEST(GraspIncline, SlidesWithTheCoulombAcceleration) {
  for (double mu : {0.0, 0.3, 0.5, 1.0}) {
    for (double theta_deg : {30.0, 50.0}) {
      const double theta = theta_deg * kPi / 180.0;
      if (std::tan(theta) <= 1.05 * mu) continue;
      GraspDef def = MilligramCubeDef();
      def.shape.box_size_m.z() = 0.25e-3;  // flat: it does not tip below tan(theta) = 4
      def.table_friction = mu;
      const testing::InclineResult r = testing::RunIncline(def, theta, 0.05, 0.2);
      const double exact = 9.81 * (std::sin(theta) - mu * std::cos(theta));
      EXPECT_NEAR(r.acceleration_m_per_s2, exact, 0.01 * exact)
          << "mu " << mu << " theta " << theta_deg;
    }
  }
}

// ---- two-jaw grasp -----------------------------------------------------------------------------

TEST(GraspHold, ThresholdIsWeightOverTwoMu) {
  for (double mu : {0.3, 0.8}) {
    const GraspDef def = MilligramCubeDef(mu);
    const testing::HoldThreshold t = testing::FindHoldThreshold(def, 1e-3, 14);
    // Independent of the model: m = rho V of the cube.
    const double m = def.density_kg_per_m3 * 1e-9;
    const double exact = m * 9.81 / (2.0 * mu);
    EXPECT_GT(t.held_grip_N, t.dropped_grip_N);
    EXPECT_LT(t.held_grip_N - t.dropped_grip_N, 0.02 * exact) << "bisection too coarse";
    EXPECT_NEAR(t.threshold_N(), exact, 0.03 * exact) << "mu " << mu;
  }
}

TEST(GraspHold, AlignedGraspLiftsWithoutRotation) {
  const GraspDef def = MilligramCubeDef(0.5);
  testing::LiftOptions o;
  o.squeeze_m = 40e-6;
  const testing::LiftResult r = testing::RunLift(def, 1e-3, o);
  EXPECT_TRUE(r.lifted);
  EXPECT_NEAR(r.rise_m, o.lift_m, 0.02 * o.lift_m);
  EXPECT_LT(r.final.metrics.max_induced_rotation_rad, kAlignedRotationTol_rad);
  // The cube settles on the table by the spring's sag before the jaws touch (at most
  // g h^2 / table_stiffness_limit, about a micrometre): the closing line passes that far above
  // its centre.
  const double sag_m = 9.81 * 1e-6 / def.contact.table_stiffness_limit;
  EXPECT_LT(r.final.metrics.alignment_angle_rad, 1e-5);
  EXPECT_LT(r.final.metrics.closing_offset_m, 1.01 * sag_m);
  EXPECT_EQ(r.final.metrics.drops, 0);
  EXPECT_EQ(r.final.metrics.lifts, 1);
  EXPECT_TRUE(r.final.metrics.held);
  // Held still in the air: the jaws carry the weight, and the tool feels it.
  EXPECT_NEAR(r.final.out.f_T_W.z(), -MakeGraspModel(def).weight_N,
              1e-3 * MakeGraspModel(def).weight_N);
  EXPECT_LT(r.final.metrics.slip_distance_m, 1e-6);
}

// A firm, high-friction grip 0.3 mm off the centre of a 3 mm bar holds it still in the air; the
// tool then carries the bar's weight acting at its centre of mass: f = m g and, about the tool
// origin, tau = (p_WO - p_WT) x m g (statics, independent of the contact details).
TEST(GraspHold, OffsetHoldTransmitsTheWeightAndItsMoment) {
  GraspDef def = MilligramCubeDef(1.5);
  def.shape.box_size_m = Eigen::Vector3d(3e-3, 1e-3, 1e-3);
  const GraspModel model = MakeGraspModel(def);
  testing::LiftOptions o;
  o.offset_x_m = 0.3e-3;
  o.squeeze_m = 150e-6;
  const testing::LiftResult r = testing::RunLift(def, 1e-3, o);
  ASSERT_TRUE(r.lifted);
  EXPECT_LT(r.final.metrics.max_induced_rotation_rad, kAlignedRotationTol_rad);
  const Eigen::Vector3d weight_W = model.mass_kg * def.gravity_m_per_s2;
  const Eigen::Vector3d tau_W = (r.final.X_WO.p_W - r.final.X_WT.p_W).cross(weight_W);
  EXPECT_LT((r.final.out.f_T_W - weight_W).norm(), 1e-3 * weight_W.norm());
  EXPECT_NEAR(tau_W.y(), -0.3e-3 * model.weight_N, 0.01 * 0.3e-3 * model.weight_N);
  EXPECT_LT((r.final.out.tau_T_W - tau_W).norm(), 0.01 * tau_W.norm());
}

TEST(GraspHold, WeakGripLeavesItOnTheTable) {
  const GraspDef def = MilligramCubeDef(0.5);
  testing::LiftOptions o;
  const double exact = 1e-6 * 9.81 / (2.0 * 0.5);
  // A squeeze whose grip is well under the threshold (the face's line samples share the
  // stiffness, so aim low and check the measured grip).
  o.squeeze_m = 2e-6;
  const testing::LiftResult r = testing::RunLift(def, 1e-3, o);
  ASSERT_LT(r.grip_force_N, 0.9 * exact);
  ASSERT_GT(r.grip_force_N, 0.0);
  EXPECT_FALSE(r.lifted);
  EXPECT_LT(r.rise_m, 0.05 * o.lift_m);
  EXPECT_GT(r.final.metrics.slip_distance_m, 0.5 * o.lift_m) << "the jaws slid along it";
}

TEST(GraspHold, OpeningTheJawsInTheAirIsADrop) {
  const GraspDef def = MilligramCubeDef(0.5);
  const GraspModel model = MakeGraspModel(def);
  testing::LiftOptions o;
  o.squeeze_m = 40e-6;
  testing::LiftResult r = testing::RunLift(def, 1e-3, o);
  ASSERT_TRUE(r.lifted);
  GraspState state = r.final;
  GraspWorkspace w;
  GraspInput in;
  in.X_WT.linear() = Eigen::Quaterniond(state.X_WT.q()).toRotationMatrix();
  in.X_WT.translation() = state.X_WT.p_W;
  in.gripper = 0.0;  // open
  for (int k = 0; k < 300; ++k) StepGrasp(model, in, w, state);
  EXPECT_EQ(state.metrics.drops, 1);
  EXPECT_FALSE(state.metrics.held);
  EXPECT_LT(state.X_WO.p_W.z(), 0.6e-3) << "back on the table";
}

TEST(GraspMisaligned, OffsetClosingLineTiltsTheCentreOfMassDown) {
  GraspDef def = MilligramCubeDef(0.5);
  def.shape.box_size_m = Eigen::Vector3d(3e-3, 1e-3, 1e-3);
  const double weight = def.density_kg_per_m3 * 3e-9 * 9.81;
  testing::LiftOptions o;
  o.offset_x_m = 1e-3;  // grip at x = +1 mm: gravity at the centre turns the body about -y
  o.squeeze_m = 1.5 * weight / (2.0 * 0.5) / (9.0 / 4.0);  // about 1.5x the hold threshold
  const testing::LiftResult r = testing::RunLift(def, 1e-3, o);
  EXPECT_NEAR(r.final.metrics.closing_offset_m, 1e-3, 1e-6);
  // The torque of gravity about the grip, (-1 mm, 0, 0) x (0, 0, -m g), is along -y.
  EXPECT_LT(r.rotation_y_rad, -5.0 * kPi / 180.0);
  EXPECT_GT(r.final.metrics.max_induced_rotation_rad, 5.0 * kPi / 180.0);
}

// Jaws at an angle a to a cube's faces touch two opposite vertical edges; the line between the
// contacts makes 45° - a with the jaws' normal. The grasp holds the cube still when that line
// lies inside both friction cones, 45° - |a| <= atan(mu) (the antipodal force-closure condition,
// Nguyen, IJRR 7(3), 1988); otherwise the edges slip and the cube turns until its faces lie on
// the jaws, in the sense of the jaws' torque: jaw + pushes the edge (-h, h) along
// (sin a, -cos a), whose torque about z, h (cos a - sin a) f, has the sign of a.
TEST(GraspMisaligned, JawsAtAnAngleTurnTheCubeUnlessTheGraspIsInTheFrictionCones) {
  struct Case {
    double mu, yaw_deg;
  };
  for (const Case& k : {Case{0.2, 20.0}, Case{0.2, -20.0}, Case{0.5, 10.0}, Case{0.2, 40.0},
                        Case{0.5, -25.0}, Case{0.5, 30.0}}) {
    GraspDef def = MilligramCubeDef(k.mu);
    def.table_friction = 0.0;
    testing::LiftOptions o;
    o.yaw_rad = k.yaw_deg * kPi / 180.0;
    o.squeeze_m = 40e-6;
    o.lift_m = 0.0;
    o.hold_s = 0.0;
    const testing::LiftResult r = testing::RunLift(def, 1e-3, o);
    const double a = std::abs(o.yaw_rad);
    const bool in_cones = kPi / 4.0 - a <= std::atan(k.mu);
    EXPECT_NEAR(r.final.metrics.alignment_angle_rad, a, 1e-3) << k.mu << " " << k.yaw_deg;
    // The object barely turns before the jaws touch it (its settling on the table).
    const double turned = Eigen::AngleAxisd(r.final.X_WO.q()).angle();
    EXPECT_NEAR(r.final.metrics.induced_rotation_rad, turned, 1e-5) << k.mu << " " << k.yaw_deg;
    if (in_cones) {
      EXPECT_LT(std::abs(r.yaw_rad), kAlignedRotationTol_rad) << k.mu << " " << k.yaw_deg;
    } else {
      EXPECT_GT(r.yaw_rad * o.yaw_rad, 0.0) << k.mu << " " << k.yaw_deg;
      EXPECT_NEAR(r.yaw_rad, o.yaw_rad, 0.05 * a)
          << "faces onto the jaws " << k.mu << " " << k.yaw_deg;
    }
  }
}

// ---- the real-time contract --------------------------------------------------------------------

TEST(GraspContract, StepAllocatesNothing) {
  for (int substeps : {1, 3}) {
    GraspDef def = MilligramCubeDef(0.5);
    def.solver.substeps = substeps;
    const GraspModel model = MakeGraspModel(def);
    GraspState state = MakeGraspStateOnTable(model, Eigen::Vector3d::Zero());
    GraspWorkspace w;
    GraspInput in;
    in.X_WT.translation() = state.X_WO.p_W;
    microdex::testing::StartCountingAllocations();
    for (int k = 0; k < 500; ++k) {
      in.gripper = std::min(1.0, k / 200.0) * 0.34;
      in.X_WT.translation().z() += k > 300 ? 1e-6 : 0.0;
      StepGrasp(model, in, w, state);
    }
    in.gripper = std::nan("");
    StepGrasp(model, in, w, state);
    const std::uint64_t allocations = microdex::testing::StopCountingAllocations();
    EXPECT_EQ(allocations, 0u) << substeps << " sub-steps";
    EXPECT_TRUE(state.metrics.held);
  }
}

TEST(GraspContract, CopiedStateContinuesBitForBit) {
  const GraspModel model = MakeGraspModel(MilligramCubeDef(0.5));
  GraspState a = MakeGraspStateOnTable(model, Eigen::Vector3d::Zero());
  GraspWorkspace wa, wb;
  GraspInput in;
  in.X_WT.translation() = a.X_WO.p_W + Eigen::Vector3d(0.2e-3, 0.0, 0.0);
  in.X_WT.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto drive = [&](int k) {
    in.gripper = std::min(1.0, k / 200.0) * 0.34;
    in.X_WT.translation().z() += k > 300 ? 1e-6 : 0.0;
  };
  for (int k = 0; k < 400; ++k) {
    drive(k);
    StepGrasp(model, in, wa, a);
  }
  GraspState b = a;
  ASSERT_EQ(a, b);
  for (int k = 400; k < 800; ++k) {
    drive(k);
    StepGrasp(model, in, wa, a);
    StepGrasp(model, in, wb, b);
    ASSERT_EQ(a, b) << "step " << k;
  }
  EXPECT_GT(a.metrics.induced_rotation_rad, 0.0);
}

TEST(GraspContract, BadInputLeavesTheStateFiniteAndCounts) {
  const GraspModel model = MakeGraspModel(MilligramCubeDef(0.5));
  GraspState state = MakeGraspStateOnTable(model, Eigen::Vector3d::Zero());
  GraspWorkspace w;
  GraspInput in;
  in.X_WT.translation() = state.X_WO.p_W;
  in.gripper = 0.4;  // a 0.8 mm gap on the 1 mm cube
  for (int k = 0; k < 100; ++k) StepGrasp(model, in, w, state);
  const double nan = std::nan("");
  GraspInput bad = in;
  bad.X_WT.translation().x() = nan;
  StepGrasp(model, bad, w, state);
  bad = in;
  bad.gripper = nan;
  StepGrasp(model, bad, w, state);
  bad = in;
  bad.X_WT.linear()(0, 0) = std::numeric_limits<double>::infinity();
  StepGrasp(model, bad, w, state);
  bad = in;
  bad.dt_s = nan;
  const std::int64_t steps = state.steps;
  StepGrasp(model, bad, w, state);
  EXPECT_EQ(state.steps, steps) << "a bad dt skips the step";
  bad.dt_s = -1e-3;
  StepGrasp(model, bad, w, state);
  EXPECT_EQ(state.warnings.invalid_inputs, 5);
  for (int k = 0; k < 100; ++k) StepGrasp(model, in, w, state);
  EXPECT_TRUE(state.X_WO.p_W.allFinite());
  EXPECT_TRUE(state.X_WO.q_xyzw.allFinite());
  EXPECT_TRUE(state.out.f_T_W.allFinite());
  EXPECT_TRUE(state.metrics.held);
  EXPECT_EQ(state.warnings.nonfinite_resets, 0);
}

}  // namespace
}  // namespace microdex::grasp
