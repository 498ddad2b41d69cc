// Stability over stiff and extreme parameters: objects of 0.2-5 mm and 1e-12 kg to 2.5 g, friction
// 0-1.5, jaw stiffness 1 N/m to 1e7 N/m, jaws closing at up to 1 m/s. Every run must stay finite,
// keep its speed below what the jaws and the contact springs can give it, keep penetrations
// within the commanded squeeze, and, with the jaws away, never gain energy.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "common/grasp/grasp_contacts.h"
#include "common/grasp/grasp_step.h"

namespace microdex::grasp {
namespace {

// No run may move the object faster than this: 5x the fastest jaw (1 m/s). A contact spring
// gives back at most its depth per step (the soft row's bias is below C / h), which for the
// deepest commanded squeeze (10 % of 5 mm in 1 ms) is 0.5 m/s.
constexpr double kMaxSpeed_m_per_s = 5.0;

struct SweepCase {
  ShapeKind kind;
  double size_m;
  double density;
  double mu;
  double jaw_speed_m_per_s;
  double stiffness_N_per_m;
};

GraspDef SweepDef(const SweepCase& c) {
  GraspDef def;
  def.shape.kind = c.kind;
  def.shape.box_size_m = Eigen::Vector3d(c.size_m, c.size_m, c.size_m);
  def.shape.radius_m = 0.5 * c.size_m;
  def.shape.length_m = c.size_m;
  def.density_kg_per_m3 = c.density;
  def.jaw_friction = c.mu;
  def.table_friction = c.mu;
  def.jaws.width_m = 0.8 * c.size_m;
  def.jaws.length_m = 0.8 * c.size_m;
  def.jaws.thickness_m = 0.3 * c.size_m;
  def.jaws.open_gap_m = 2.0 * c.size_m;
  def.jaws.closed_gap_m = 0.8 * c.size_m;  // squeezes a tenth of the width from each side
  def.contact.jaw_stiffness_N_per_m = c.stiffness_N_per_m;
  def.contact.table_stiffness_N_per_m = std::max(c.stiffness_N_per_m, 1e3);
  return def;
}

struct SweepReport {
  bool finite = true;
  double max_speed_m_per_s = 0.0;
  double max_jaw_excess_m = 0.0;  // deepest jaw contact beyond the jaws' total overlap
  double max_table_penetration_m = 0.0;
  GraspWarnings warnings;
};

// Close at the jaw speed, hold, lift by half the size, hold, open at the jaw speed, let fall.
SweepReport RunSweepCase(const SweepCase& c) {
  const GraspDef def = SweepDef(c);
  const GraspModel model = MakeGraspModel(def);
  GraspState state = MakeGraspStateOnTable(model, Eigen::Vector3d::Zero());
  GraspWorkspace w;
  GraspInput in;
  in.X_WT.linear() = Eigen::AngleAxisd(0.17, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d p0 = state.X_WO.p_W;
  const double travel = 0.5 * (def.jaws.open_gap_m - def.jaws.closed_gap_m);  // per jaw
  const double close_s = travel / c.jaw_speed_m_per_s;
  const double lift_speed = std::min(c.jaw_speed_m_per_s, 0.05);
  const double lift_s = 0.5 * c.size_m / lift_speed;
  const double t_close = close_s, t_hold = t_close + 0.05, t_lift = t_hold + lift_s;
  const double t_hold2 = t_lift + 0.05, t_open = t_hold2 + close_s, t_end = t_open + 0.2;
  SweepReport r;
  const int steps = static_cast<int>(std::ceil(t_end / in.dt_s));
  for (int k = 1; k <= steps; ++k) {
    const double t = k * in.dt_s;
    double g = 1.0;
    if (t < t_close) g = t / close_s;
    if (t > t_hold2) g = std::max(0.0, 1.0 - (t - t_hold2) / close_s);
    const double lift = 0.5 * c.size_m * std::clamp((t - t_hold) / lift_s, 0.0, 1.0);
    in.gripper = g;
    in.X_WT.translation() = p0 + Eigen::Vector3d(0.0, 0.0, lift);
    StepGrasp(model, in, w, state);
    r.finite = r.finite && state.X_WO.p_W.allFinite() && state.v_WO.allFinite() &&
               state.w_WO.allFinite() && state.out.f_T_W.allFinite();
    const double speed = state.v_WO.norm() + state.w_WO.norm() * model.shape.bounding_radius_m;
    r.max_speed_m_per_s = std::max(r.max_speed_m_per_s, speed);
    r.max_table_penetration_m = std::max(r.max_table_penetration_m,
                                         -CalcLowestPoint(model, state.X_WO.p_W, state.X_WO.q()));
    // Jaw penetration after the step: the deepest jaw contact of a fresh contact pass.
    GraspWorkspace probe;
    probe.X_WT0 = probe.X_WT1 = in.X_WT;
    probe.gripper0 = probe.gripper1 = g;
    probe.faces0 = probe.faces1 = CalcJawFaces(model, in.X_WT, g);
    ContactsFromJaws(model, state, in.dt_s, probe);
    double deepest = 0.0;
    for (int i = 0; i < probe.num_contacts; ++i) {
      deepest = std::max(deepest, -probe.contacts[i].separation_m);
    }
    // The jaws' total overlap with the object as it is now: its width along the closing
    // direction (symmetric shapes) minus the gap. One jaw cannot be deeper than that unless the
    // object passes through it.
    const Eigen::Vector3d y_W = in.X_WT.linear().col(1);
    std::array<Eigen::Vector3d, kMaxSupportPoints> points;
    const Eigen::Vector3d d_O = state.X_WO.q().conjugate() * y_W;
    const int n = CalcSupportPoints(model.shape, d_O, points);
    double extent = 0.0;
    for (int i = 0; i < n; ++i) extent = std::max(extent, points[i].dot(d_O));
    const double overlap = std::max(0.0, 2.0 * extent - 2.0 * CalcHalfGap(def.jaws, g));
    r.max_jaw_excess_m = std::max(r.max_jaw_excess_m, deepest - overlap);
  }
  r.warnings = state.warnings;
  return r;
}

TEST(GraspStability, SweepOfSizesMassesFrictionStiffnessAndJawSpeed) {
  int runs = 0;
  double max_table = 0.0;
  for (ShapeKind kind : {ShapeKind::kBox, ShapeKind::kCylinder, ShapeKind::kSphere}) {
    for (double size : {0.2e-3, 1e-3, 5e-3}) {
      for (double density : {100.0, 20000.0}) {
        for (double mu : {0.0, 0.5, 1.5}) {
          for (double speed : {0.01, 1.0}) {
            for (double k : {1.0, 1e4, 1e7}) {
              const SweepCase c{kind, size, density, mu, speed, k};
              const SweepReport r = RunSweepCase(c);
              ++runs;
              const std::string what =
                  std::string(ShapeKindName(kind)) + " size " + std::to_string(size) + " density " +
                  std::to_string(density) + " mu " + std::to_string(mu) + " speed " +
                  std::to_string(speed) + " k " + std::to_string(k);
              ASSERT_TRUE(r.finite) << what;
              EXPECT_EQ(r.warnings, GraspWarnings{}) << what;
              EXPECT_LT(r.max_speed_m_per_s, kMaxSpeed_m_per_s) << what;
              // A jaw moves at most speed * dt within a step beyond where the overlap was.
              EXPECT_LT(r.max_jaw_excess_m, speed * 1e-3 + 1e-9) << what;
              // The table: no sinking into it beyond a tenth of the size, whatever the jaws do.
              EXPECT_LT(r.max_table_penetration_m, 0.1 * size) << what;
              max_table = std::max(max_table, r.max_table_penetration_m / size);
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(runs, 324);
  std::printf("deepest table penetration: %.3g of the size\n", max_table);
}

// With the jaws away, the object and the table are a closed system: dropped, spinning and
// sliding, its kinetic plus potential energy never rises (the soft contact's stored energy is
// not counted, which only lowers the measured sum while it is compressed).
TEST(GraspStability, DroppedObjectNeverGainsEnergy) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int runs = 0;
  for (ShapeKind kind : {ShapeKind::kBox, ShapeKind::kCylinder, ShapeKind::kSphere}) {
    for (double size : {0.2e-3, 5e-3}) {
      for (double density : {100.0, 20000.0}) {
        for (double mu : {0.0, 0.5, 1.5}) {
          for (double k : {1e3, 1e7}) {
            SweepCase c{kind, size, density, mu, 1.0, k};
            GraspDef def = SweepDef(c);
            def.contact.table_stiffness_N_per_m = k;
            def.shape.box_size_m = size * Eigen::Vector3d(1.0, 0.6, 0.3);
            const GraspModel model = MakeGraspModel(def);
            GraspState state;
            state.X_WO.set_q(
                Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized());
            state.X_WO.p_W = Eigen::Vector3d(0.0, 0.0, 3.0 * size);
            state.v_WO = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.05;
            state.w_WO = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.05 / size;
            auto energy = [&](const GraspState& s) {
              const Eigen::Matrix3d R = s.X_WO.q().toRotationMatrix();
              const Eigen::Vector3d w_B = R.transpose() * s.w_WO;
              return 0.5 * model.mass_kg * s.v_WO.squaredNorm() +
                     0.5 * w_B.dot(model.inertia_kg_m2.cwiseProduct(w_B)) -
                     model.mass_kg * def.gravity_m_per_s2.dot(s.X_WO.p_W);
            };
            // The initial energy (no spring compressed yet): the sum may later rise when a
            // compressed spring gives its energy back, but never above where it started.
            const double e0 = energy(state);
            GraspWorkspace w;
            GraspInput far;
            far.X_WT.translation() = Eigen::Vector3d(1.0, 1.0, 1.0);
            for (int step = 0; step < 1000; ++step) {
              StepGrasp(model, far, w, state);
              const double e = energy(state);
              ASSERT_LE(e, e0 + 1e-9 * std::abs(e0) + 1e-18)
                  << ShapeKindName(kind) << " size " << size << " density " << density << " mu "
                  << mu << " k " << k << " step " << step;
            }
            ++runs;
          }
        }
      }
    }
  }
  EXPECT_EQ(runs, 72);
}

}  // namespace
}  // namespace microdex::grasp
