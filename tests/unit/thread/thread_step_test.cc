// StepThread: no allocation in the loop, stability at the key points of the region, grasp
// forces against statics, run-time grasp and release, and adversarial tool motion.
#include "common/thread/thread_step.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include "common/thread/grasp.h"
#include "common/thread/thread_contacts.h"
#include "common/thread/thread_forces.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/thread_scenarios.h"

namespace microdex::thread {
namespace {

TEST(ThreadStep, NoAllocationPerStepAfterWarmUp) {
  // The third case: exact pair coupling and friction (the low-rank solve of the implicit step).
  for (int c = 0; c < 3; ++c) {
    const Integrator integ =
        c == 0 ? Integrator::kSemiImplicitEuler : Integrator::kLinearlyImplicitEuler;
    ThreadDef def = StiffNylon10_0();
    def.integrator = integ;
    if (c == 2) {
      def.exact_contact_pairs = 64;
      def.friction_coefficient = 0.2;
      def.object_friction_coefficient = 0.2;
    }
    // The baseline needs a time step it survives; allocation must not depend on that.
    if (integ == Integrator::kSemiImplicitEuler) {
      def.mass_scale = 1e6;
      def.time_step_s = 1e-6;
    }
    const ThreadModel model = MakeThreadModel(def);
    ThreadState state;
    const std::vector<Collider> colliders = FoldIntoUOverACapsule(model, state);
    ThreadWorkspace ws = MakeThreadWorkspace(model);
    const int a = GraspNode(model, 0, state);
    const int b = GraspNode(model, 64, state);
    for (int k = 0; k < 10; ++k) StepThread(model, colliders, ws, state);
    int most_exact = 0, most_friction = 0;
    ::microdex::testing::StartCountingAllocations();
    for (int k = 0; k < 200; ++k) {
      SetGraspTarget(state, a, Eigen::Vector3d(-1e-6 * k, 0, 0), 0.01 * k);
      SetGraspTarget(state, b, Eigen::Vector3d(-1e-6 * k, 30e-6, 1e-6 * k), 0.0);
      if (k == 100) ReleaseGrasp(state, b);
      if (k == 150) GraspNode(model, 40, state);
      StepThread(model, colliders, ws, state);
      most_exact = std::max(most_exact, state.status.num_exact_pairs);
      most_friction = std::max(most_friction, state.status.num_friction_contacts);
    }
    EXPECT_EQ(::microdex::testing::StopCountingAllocations(), 0u) << IntegratorName(integ) << c;
    EXPECT_GT(state.status.num_candidate_pairs, 0) << IntegratorName(integ);
    if (c == 2) {
      EXPECT_GT(most_exact, 0);
      EXPECT_GT(most_friction, 0);
    }
  }
}

// Key points of the stability region (the full map is microdex-bench thread --stability).
TEST(ThreadStability, BaselineUnstableAndImplicitStableAtStiffNylonOneMs) {
  SwingPullOptions opt;
  opt.time_step_s = 1e-3;
  // Per-link stretch stiffness of 10-0 nylon (E A / r ~ 3e3 N/m), its bending stiffness, and
  // the lightest node of the sweep.
  const ThreadDef def = SwingPullDef(3e3, 1e-7, 1e-7);
  opt.integrator = Integrator::kSemiImplicitEuler;
  EXPECT_FALSE(RunSwingPull(def, opt).stable());
  opt.integrator = Integrator::kLinearlyImplicitEuler;
  const SwingPullReport r = RunSwingPull(def, opt);
  EXPECT_TRUE(r.stable()) << "strain " << r.max_strain << " energy " << r.max_energy_J;
}

TEST(ThreadStability, BothStableAtSoftPointSmallStep) {
  SwingPullOptions opt;
  // k_s = 1e4 N/m, m = 1e-5 kg: the baseline's linear limit 2 / sqrt(4 k / m) is 32 us; at
  // 20 us both integrators hold. (With k_s = 1e3 N/m the swing itself stretches the undamped
  // baseline thread to 10 % at any step size: a physical strain, not an instability.)
  opt.time_step_s = 2e-5;
  const ThreadDef def = SwingPullDef(1e4, 1e-9, 1e-5);
  for (Integrator integ : {Integrator::kSemiImplicitEuler, Integrator::kLinearlyImplicitEuler}) {
    opt.integrator = integ;
    const SwingPullReport r = RunSwingPull(def, opt);
    EXPECT_TRUE(r.stable()) << IntegratorName(integ) << " strain " << r.max_strain;
  }
}

// The post-step strain limit is what keeps the linearly implicit step inside the region here:
// a light, soft thread (k_s = 1e2 N/m, m = 1e-5 kg) swung at 1 ms.
TEST(ThreadStability, StrainLimitKeepsImplicitStepInsideAtOneMs) {
  SwingPullOptions opt;
  opt.time_step_s = 1e-3;
  ThreadDef def = SwingPullDef(1e2, 1e-9, 1e-5);
  const SwingPullReport limited = RunSwingPull(def, opt);
  EXPECT_TRUE(limited.stable()) << "strain " << limited.max_strain;
  def.strain_limit = 0.0;
  const SwingPullReport free = RunSwingPull(def, opt);
  EXPECT_FALSE(free.strain_ok) << "strain " << free.max_strain;
}

// Stiff and heavy threads swung with large steps: one linearised step rotates links far and
// lengthens them; the direct strain-band solve inside the contact projection brings every link
// back (the Gauss-Seidel sweeps it replaced left 11.9 % and 36 % here: stability map, README).
TEST(ThreadStability, DirectStrainBandHoldsStiffThreadsAtLargeSteps) {
  struct Point {
    double ks, kb, m, dt;
  };
  for (const Point p :
       {Point{1e8, 1e-9, 1e-2, 1e-3}, Point{1e6, 1e-9, 1e-5, 4e-3}, Point{1e8, 1e-3, 1e-3, 4e-3}}) {
    SwingPullOptions opt;
    opt.time_step_s = p.dt;
    const SwingPullReport r = RunSwingPull(SwingPullDef(p.ks, p.kb, p.m), opt);
    EXPECT_TRUE(r.stable()) << p.ks << " " << p.kb << " " << p.m << " " << p.dt << ": strain "
                            << r.max_strain;
    EXPECT_LT(r.max_strain, 0.08) << p.ks << " " << p.kb << " " << p.m << " " << p.dt;
  }
}

TEST(ThreadStability, StiffNylonPresetSwungAtOneMs) {
  for (Integrator integ : {Integrator::kSemiImplicitEuler, Integrator::kLinearlyImplicitEuler}) {
    const ThreadModel model = MakeThreadModel(StiffNylon10_0());
    ThreadState state =
        MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
    ThreadWorkspace ws = MakeThreadWorkspace(model);
    const int slot = GraspNode(model, 0, state);
    bool ok = true;
    for (int k = 1; k <= 500; ++k) {
      const double t = 1e-3 * k;
      SetGraspTarget(state, slot, Eigen::Vector3d(0.0, 0.01 * std::sin(10 * t), 0.0), 0.0);
      StepThreadWith(model, integ, 1e-3, {}, ws, state);
      ok = ok && state.status.nonfinite_resets == 0 && state.status.factorization_failures == 0 &&
           state.status.max_strain < 0.1;
    }
    if (integ == Integrator::kSemiImplicitEuler) {
      EXPECT_FALSE(ok);
    } else {
      EXPECT_TRUE(ok) << "strain " << state.status.max_strain;
    }
    EXPECT_TRUE(state.x_W.allFinite());  // a failed step rolls back, never NaN
  }
}

TEST(ThreadGrasp, HangingThreadPullsTheToolWithItsWeight) {
  for (Integrator integ : {Integrator::kSemiImplicitEuler, Integrator::kLinearlyImplicitEuler}) {
    ThreadDef def = SwingPullDef(1e3, 1e-7, 1e-5);
    def.drag_N_s_per_m2 = 1.0;  // settle quickly
    const ThreadModel model = MakeThreadModel(def);
    ThreadState state =
        MakeStraightThreadState(model, Eigen::Vector3d::Zero(), -Eigen::Vector3d::UnitZ());
    ThreadWorkspace ws = MakeThreadWorkspace(model);
    const int slot = GraspNode(model, 0, state);
    const double h = integ == Integrator::kSemiImplicitEuler ? 5e-5 : 1e-3;
    const int steps = static_cast<int>(2.0 / h);
    for (int k = 0; k < steps; ++k) StepThreadWith(model, integ, h, {}, ws, state);
    const double weight_N = model.mass_kg.sum() * 9.81;
    const Eigen::Vector3d f = GraspForce(state, slot, 1.0);
    // The grasped node's own weight is carried by the tool too.
    EXPECT_NEAR(f.z(), -weight_N, 1e-3 * weight_N) << IntegratorName(integ);
    EXPECT_NEAR(f.head<2>().norm(), 0.0, 1e-3 * weight_N);
  }
}

TEST(ThreadGrasp, GraspAndReleaseAnyNodeAtRunTime) {
  const ThreadModel model = MakeThreadModel(StiffNylon10_0());
  ThreadState state =
      MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  EXPECT_EQ(GraspNode(model, -1, state), -1);
  EXPECT_EQ(GraspNode(model, model.num_nodes, state), -1);
  const int a = GraspNode(model, 10, state);
  ASSERT_GE(a, 0);
  EXPECT_EQ(GraspNode(model, 10, state), a);
  const Eigen::Vector3d target = state.x_W.col(10) + Eigen::Vector3d(0, 1e-3, 0);
  SetGraspTarget(state, a, target, 0.5);
  StepThread(model, {}, ws, state);
  EXPECT_LT((state.x_W.col(10) - target).norm(), 1e-12);
  EXPECT_NEAR(state.q_rad[10], 0.5, 1e-12);
  EXPECT_GT(state.grasps[a].f_T_W.norm(), 0.0);  // the thread resists the tug
  // The roll propagates along the thread (5.6).
  for (int k = 0; k < 200; ++k) StepThread(model, {}, ws, state);
  EXPECT_GT(state.q_rad[20], 0.01);
  ReleaseGrasp(state, a);
  const Eigen::Vector3d before = state.x_W.col(10);
  SetGraspTarget(state, a, Eigen::Vector3d(1, 1, 1), 0.0);  // ignored: released
  StepThread(model, {}, ws, state);
  EXPECT_LT((state.x_W.col(10) - before).norm(), 1e-3);
  for (int i = 0; i < model.def.max_grasps; ++i) EXPECT_GE(GraspNode(model, i, state), 0);
  EXPECT_EQ(GraspNode(model, 50, state), -1);  // all slots taken
}

// Random, jerky, extreme tool motion, including 10 cm teleports of a grasped node and grasps
// moved between nodes: never a NaN, and once the tools let go the thread returns to its rest
// length within a bounded time.
TEST(ThreadAdversarial, JerkyExtremeMotionNeverNaNAndRecovers) {
  ThreadDef def = StiffNylon10_0();
  def.num_nodes = 33;
  def.length_m = 0.015;
  const ThreadModel model = MakeThreadModel(def);
  ThreadState state =
      MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> node(0, model.num_nodes - 1);
  int slots[2] = {GraspNode(model, 0, state), GraspNode(model, model.num_nodes - 1, state)};
  const std::vector<Collider> colliders = {
      Collider::Plane(Eigen::Vector3d(0, 0, -0.002), Eigen::Vector3d::UnitZ()),
      Collider::Sphere(Eigen::Vector3d(0.007, 0.0, 0.0), 0.001)};
  const int steps = 200000;
  long long nonfinite = 0;
  for (int k = 0; k < steps; ++k) {
    for (int s = 0; s < 2; ++s) {
      Grasp& g = state.grasps[slots[s]];
      Eigen::Vector3d p = g.p_WT + 2e-3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      if (k % 5000 == 2500 * s) p += 0.1 * Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      p = p.cwiseMax(-0.2).cwiseMin(0.2);
      SetGraspTarget(state, slots[s], p, 10.0 * u(rng));
    }
    if (k % 7919 == 0) {  // move one tool to another node
      const int s = k % 2;
      ReleaseGrasp(state, slots[s]);
      slots[s] = GraspNode(model, node(rng), state);
      ASSERT_GE(slots[s], 0);
    }
    StepThread(model, colliders, ws, state);
    if (!state.x_W.allFinite() || !state.v_W.allFinite() || !state.q_rad.allFinite()) {
      ++nonfinite;
    }
    for (int s = 0; s < 2; ++s) {
      ASSERT_TRUE(GraspForce(state, slots[s], 10.0).allFinite());
    }
  }
  EXPECT_EQ(nonfinite, 0);
  // Let go of one tool, hold the other still: back to rest length within 2 s.
  ReleaseGrasp(state, slots[1]);
  int recovered_at = -1;
  for (int k = 0; k < 2000; ++k) {
    StepThread(model, colliders, ws, state);
    if (CalcMaxStrain(model, state.x_W) < 0.01) {
      recovered_at = k;
      break;
    }
  }
  EXPECT_GE(recovered_at, 0) << "strain " << CalcMaxStrain(model, state.x_W);
}

}  // namespace
}  // namespace microdex::thread
