// Forces of common/thread/thread_forces.cc against central differences of their energies,
// and invariants (zero net force, no force at rest).
#include "common/thread/thread_forces.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/support/thread_scenarios.h"

namespace microdex::thread {
namespace {

ThreadModel SmallModel() {
  ThreadDef def = SwingPullDef(50.0, 2e-4, 1e-5);
  def.num_nodes = 9;
  def.length_m = 0.01;
  return MakeThreadModel(def);
}

Eigen::Matrix3Xd Jiggled(const ThreadModel& model, double amplitude_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ThreadState s = MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  for (int i = 0; i < model.num_nodes; ++i) {
    s.x_W.col(i) += amplitude_m * Eigen::Vector3d(u(rng), u(rng), u(rng));
  }
  return s.x_W;
}

template <typename Energy, typename Force>
void ExpectForceIsMinusGradient(const ThreadModel& model, const Eigen::Matrix3Xd& x, Energy energy,
                                Force force) {
  Eigen::Matrix3Xd f = Eigen::Matrix3Xd::Zero(3, model.num_nodes);
  force(x, f);
  const double step_m = 1e-9;
  for (int i = 0; i < model.num_nodes; ++i) {
    for (int r = 0; r < 3; ++r) {
      Eigen::Matrix3Xd xp = x, xm = x;
      xp(r, i) += step_m;
      xm(r, i) -= step_m;
      const double grad = (energy(xp) - energy(xm)) / (2 * step_m);
      const double scale = f.cwiseAbs().maxCoeff();
      EXPECT_NEAR(f(r, i), -grad, 1e-5 * scale) << "node " << i << " coord " << r;
    }
  }
  // Internal forces sum to zero (momentum).
  EXPECT_LT(f.rowwise().sum().norm(), 1e-9 * f.cwiseAbs().maxCoeff());
}

TEST(ThreadForces, StretchIsMinusGradientOfItsEnergy) {
  const ThreadModel model = SmallModel();
  const Eigen::Matrix3Xd x = Jiggled(model, 0.3 * model.rest_length_m[0], 1);
  ExpectForceIsMinusGradient(
      model, x, [&](const Eigen::Matrix3Xd& y) { return CalcStretchEnergy(model, y); },
      [&](const Eigen::Matrix3Xd& y, Eigen::Matrix3Xd& f) {
        AddStretchForces(model, y, f, nullptr, 0.0);
      });
}

TEST(ThreadForces, BendIsMinusGradientOfItsEnergy) {
  const ThreadModel model = SmallModel();
  const Eigen::Matrix3Xd x = Jiggled(model, 0.3 * model.rest_length_m[0], 2);
  ExpectForceIsMinusGradient(
      model, x, [&](const Eigen::Matrix3Xd& y) { return CalcBendEnergy(model, y); },
      [&](const Eigen::Matrix3Xd& y, Eigen::Matrix3Xd& f) {
        AddBendForces(model, y, f, nullptr, 0.0);
      });
}

TEST(ThreadForces, SingleStretchedLinkPullsWithHookesLaw) {
  const ThreadModel model = SmallModel();
  ThreadState s = MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  const double stretch_m = 1e-4;
  for (int i = 5; i < model.num_nodes; ++i) s.x_W(0, i) += stretch_m;  // link 4 longer
  Eigen::Matrix3Xd f = Eigen::Matrix3Xd::Zero(3, model.num_nodes);
  AddStretchForces(model, s.x_W, f, nullptr, 0.0);
  const double expected_N = model.stretch_k_N_per_m[4] * stretch_m;
  EXPECT_NEAR(f(0, 4), expected_N, 1e-12);
  EXPECT_NEAR(f(0, 5), -expected_N, 1e-12);
  EXPECT_NEAR(f.col(0).norm(), 0.0, 1e-12);
}

TEST(ThreadForces, StraightThreadAtRestHasNoElasticForce) {
  const ThreadModel model = SmallModel();
  const ThreadState s =
      MakeStraightThreadState(model, Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 1, 0));
  Eigen::Matrix3Xd f = Eigen::Matrix3Xd::Zero(3, model.num_nodes);
  AddStretchForces(model, s.x_W, f, nullptr, 0.0);
  AddBendForces(model, s.x_W, f, nullptr, 0.0);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ThreadForces, RightAngleBendTorqueMatchesKappaTheta) {
  // Three nodes bent by 90 degrees: the end node feels k theta / r perpendicular to its link.
  ThreadDef def = SwingPullDef(50.0, 2e-4, 1e-5);
  def.num_nodes = 3;
  def.length_m = 0.002;
  const ThreadModel model = MakeThreadModel(def);
  const double r = model.rest_length_m[0];
  Eigen::Matrix3Xd x(3, 3);
  x.col(0) = Eigen::Vector3d(-r, 0, 0);
  x.col(1) = Eigen::Vector3d(0, 0, 0);
  x.col(2) = Eigen::Vector3d(0, r, 0);
  Eigen::Matrix3Xd f = Eigen::Matrix3Xd::Zero(3, 3);
  AddBendForces(model, x, f, nullptr, 0.0);
  const double expected_N = model.bend_k_N_m[1] * (M_PI / 2) / r;
  EXPECT_NEAR(f.col(2).norm(), expected_N, 1e-9 * expected_N);
  EXPECT_NEAR(f(1, 2), 0.0, 1e-9 * expected_N);  // perpendicular to link 1 (along y)
  EXPECT_GT(f(0, 2), 0.0);                       // straightening: pushed towards +x
}

TEST(ThreadForces, TwistTorquesPropagateAndSumToZero) {
  const ThreadModel model = SmallModel();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.num_nodes);
  q[0] = 1.0;  // the grasped end rolled by 1 rad
  Eigen::VectorXd tau(model.num_nodes);
  CalcTwistTorques(model, q, tau);
  EXPECT_NEAR(tau[0], -model.twist_k_N_m[0], 1e-15);
  EXPECT_NEAR(tau[1], model.twist_k_N_m[0], 1e-15);
  EXPECT_NEAR(tau.sum(), 0.0, 1e-15);
}

}  // namespace
}  // namespace microdex::thread
