// Two tools, one in each hand: the scene's second_hand section, the second tool in the state
// and its hash, the thread held at both ends by the two tools (each feels the thread's
// tension, equal and opposite, E A ε: Hooke's law for a straight uniform chain), the second
// simulated hand, and the haptic loop's check of the number of devices.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <stdexcept>

#include "common/base/input_error.h"
#include "common/state/state_hash.h"
#include "station/haptic_loop.h"
#include "station/sim_trainee.h"
#include "station/station_step.h"
#include "tests/support/alloc_counter.h"

namespace microdex::station {
namespace {

std::string SceneDir() {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes";
}

// The 30 mm nylon held by the second tool at the origin and by the first at x = 31 mm.
std::string TwoHandText(const std::string& second_hand_position) {
  return R"(
name: test-two-hands
modules: [thread]
thread:
  params: thread_stiff_nylon_10_0.yaml
  anchor_m: [0, 0, 0]
  max_strain: 0.03
second_hand: {position_m: )" +
         second_hand_position + R"(}
task: {path: line, line_start_m: [0.029, 0, 0], line_end_m: [0.030, 0, 0], time_limit_s: 60}
haptic: {rate_hz: 1000, max_force_N: 2.0}
)";
}

scene::SceneModel TwoHandScene() {
  return scene::ParseScene(TwoHandText("[0, 0, 0]"), SceneDir() + "/inline.yaml");
}

DeviceSample At(const Eigen::Vector3d& p_W) {
  DeviceSample d;
  d.X_WT.translation() = p_W;
  d.gripper = 1;
  return d;
}

TEST(Bimanual, TheSceneNamesASecondHandWhoseStartHoldsTheThread) {
  const scene::SceneModel scene = TwoHandScene();
  EXPECT_EQ(scene.hands(), 2);
  EXPECT_LT(scene.CalcIdealSecondToolPose(3.0).translation().norm(), 1e-15);
  // The second tool must start where it holds the thread.
  try {
    scene::ParseScene(TwoHandText("[0.001, 0, 0]"), SceneDir() + "/inline.yaml");
    FAIL() << "a second hand away from the thread's anchor was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("second_hand.position_m"), std::string::npos) << e.what();
  }
  try {
    scene::ParseScene(TwoHandText("[0, 0, 0], grip: 1"), SceneDir() + "/inline.yaml");
    FAIL() << "an unknown key was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grip"), std::string::npos) << e.what();
  }
  // One-handed scenes are unchanged.
  const scene::SceneModel one = scene::LoadScene(SceneDir() + "/nylon_loop.yaml");
  EXPECT_EQ(one.hands(), 1);
  Simulation sim(one);
  EXPECT_FALSE(sim.MakeInitialState(1).second_tool.has_value());
}

TEST(Bimanual, BothToolsFeelTheStretchedThreadsTensionEqualAndOpposite) {
  const scene::SceneModel scene = TwoHandScene();
  const thread::ThreadDef& def = scene.thread->def;
  const double area_m2 = std::numbers::pi * def.diameter_m * def.diameter_m / 4;
  const double strain = 0.01;
  const double tension_N = def.youngs_modulus_Pa * area_m2 * strain;
  // The second tool moves the held end from the origin to −5 mm (carrying the thread) while
  // the first stretches it to ε: the chain's two ends at L (1 + ε) apart along x.
  const Eigen::Vector3d p2_end(-5e-3, 0, 0);
  const Eigen::Vector3d p1_start = scene.CalcIdealToolPose(0).translation();
  const Eigen::Vector3d p1_end = p2_end + def.length_m * (1 + strain) * Eigen::Vector3d::UnitX();
  Simulation sim(scene);
  state::StationState s = sim.MakeInitialState(7);
  ASSERT_TRUE(s.second_tool.has_value());
  const int ramp = 1500, hold = 1500;
  for (int k = 0; k < ramp + hold; ++k) {
    const double u = std::min(1.0, static_cast<double>(k + 1) / ramp);
    StationInput in;
    in.device = At(p1_start + u * (p1_end - p1_start));
    in.second = At(u * p2_end);
    StepStation(sim, in, s);
  }
  const Eigen::Vector3d f1 = s.tool.f_T_W;
  const Eigen::Vector3d f2 = s.second_tool->f_T_W;
  // The first tool is pulled back (−x), the second forward (+x), each by E A ε.
  EXPECT_NEAR(f1.x(), -tension_N, 0.02 * tension_N);
  EXPECT_NEAR(f2.x(), tension_N, 0.02 * tension_N);
  EXPECT_LT((f1 + f2).norm(), 0.02 * tension_N);
  // The held end followed the second tool.
  EXPECT_LT((s.thread->thread.x_W.col(0) - p2_end).norm(), 1e-6);
  EXPECT_EQ(s.second_tool->gripper, 1);
}

TEST(Bimanual, TheSecondToolIsStateItsHashSeesItAndAStepIsDeterministic) {
  const scene::SceneModel scene = TwoHandScene();
  Simulation sim(scene);
  const Eigen::Vector3d p1 = scene.CalcIdealToolPose(0).translation();
  auto run = [&](double second_dx_m) {
    state::StationState s = sim.MakeInitialState(3);
    for (int k = 0; k < 50; ++k) {
      StationInput in;
      in.device = At(p1);
      in.second = At(Eigen::Vector3d(k == 20 ? second_dx_m : 0, 0, 0));
      StepStation(sim, in, s);
    }
    return s;
  };
  const state::StationState a = run(0), b = run(0), c = run(1e-9);
  EXPECT_TRUE(a == b);
  EXPECT_EQ(state::CalcStateHash(a), state::CalcStateHash(b));
  // A nanometre in the second hand at one step: a different state and hash.
  EXPECT_FALSE(a == c);
  EXPECT_NE(state::CalcStateHash(a), state::CalcStateHash(c));
  // A copy steps on exactly as the original.
  state::StationState copy = a, orig = a;
  StationInput in;
  in.device = At(p1);
  in.second = At(Eigen::Vector3d(2e-4, 0, 0));
  StepStation(sim, in, copy);
  StepStation(sim, in, orig);
  EXPECT_TRUE(copy == orig);
}

TEST(Bimanual, AFaultOnTheSecondDeviceRampsItsForceToZero) {
  const scene::SceneModel scene = TwoHandScene();
  Simulation sim(scene);
  const thread::ThreadDef& def = scene.thread->def;
  state::StationState s = sim.MakeInitialState(1);
  const Eigen::Vector3d p1_end = def.length_m * 1.01 * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d p1_start = scene.CalcIdealToolPose(0).translation();
  for (int k = 0; k < 1500; ++k) {
    StationInput in;
    in.device = At(p1_start + std::min(1.0, (k + 1) / 1000.0) * (p1_end - p1_start));
    in.second = At(Eigen::Vector3d::Zero());
    StepStation(sim, in, s);
  }
  const double before = s.second_tool->f_T_W.norm();
  ASSERT_GT(before, 1e-3);
  double prev = before;
  bool reached_zero = false;
  for (int k = 0; k < 2000 && !reached_zero; ++k) {
    StationInput in;
    in.device = At(p1_end);
    in.second = At(Eigen::Vector3d::Zero());
    in.second.fault = DeviceFault::kTimeout;
    StepStation(sim, in, s);
    const double now = s.second_tool->f_T_W.norm();
    EXPECT_LE(now, prev + 1e-15) << "step " << k;  // falls monotonically
    prev = now;
    reached_zero = now == 0;
  }
  EXPECT_TRUE(reached_zero);
  EXPECT_EQ(s.second_tool->device_fault, static_cast<std::uint8_t>(DeviceFault::kTimeout));
  // The first tool is not at fault and keeps feeling the thread.
  EXPECT_GT(s.tool.f_T_W.norm(), 1e-3);
}

TEST(Bimanual, TheSecondSimulatedHandHoldsItsPoseWithATremorOfItsOwn) {
  const scene::SceneModel scene = TwoHandScene();
  SimTraineeDef def;
  def.skill = 0.3;
  def.seed = 11;
  SimTrainee first(scene, def);
  def.hand = 1;
  SimTrainee second(scene, def), again(scene, def);
  const Eigen::Vector3d hold = scene.CalcIdealSecondToolPose(0).translation();
  double sq = 0, acc1_max = 0, acc_apart_max = 0;
  const int n = 3000;
  Eigen::Vector3d a_prev[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  Eigen::Vector3d b_prev[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d a = first.Read(k).X_WT.translation();
    const DeviceSample b = second.Read(k);
    EXPECT_EQ(b.gripper, 1);
    EXPECT_EQ(b.buttons, 0u);
    // Deterministic: the same definition gives the same hand.
    EXPECT_EQ(b.X_WT.translation(), again.Read(k).X_WT.translation());
    sq += (b.X_WT.translation() - hold).squaredNorm();
    // Second differences over 1 ms: the 8–12 Hz tremor dominates them (the paths and the
    // drift are smooth), so equal tremor streams would make them equal.
    if (k >= 2) {
      const Eigen::Vector3d acc1 = a - 2 * a_prev[1] + a_prev[0];
      const Eigen::Vector3d acc2 = b.X_WT.translation() - 2 * b_prev[1] + b_prev[0];
      acc1_max = std::max(acc1_max, acc1.norm());
      acc_apart_max = std::max(acc_apart_max, (acc2 - acc1).norm());
    }
    a_prev[0] = a_prev[1], a_prev[1] = a;
    b_prev[0] = b_prev[1], b_prev[1] = b.X_WT.translation();
  }
  const double rms = std::sqrt(sq / n);
  // Tremor and drift of a skill-0.3 hand: tens to hundreds of micrometres, never millimetres.
  EXPECT_GT(rms, 5e-6);
  EXPECT_LT(rms, 1e-3);
  // A tremor of its own, not the first hand's.
  ASSERT_GT(acc1_max, 0);
  EXPECT_GT(acc_apart_max, 0.2 * acc1_max);
  SimTraineeDef bad;
  bad.hand = 2;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

TEST(Bimanual, TheHapticLoopNeedsOneDevicePerHand) {
  const scene::SceneModel two = TwoHandScene();
  const scene::SceneModel one = scene::LoadScene(SceneDir() + "/nylon_loop.yaml");
  SimTrainee d1(two, {});
  HeldDevice d2(two.CalcIdealSecondToolPose(0));
  StationRings rings(64, 8);
  rt::ManualClock clock(0);
  EXPECT_THROW(HapticLoop(two, d1, rings, clock, {}), std::invalid_argument);
  EXPECT_THROW(HapticLoop(one, d1, rings, clock, {}, &d2), std::invalid_argument);
  HapticLoop loop(two, d1, rings, clock, {}, &d2);
  loop.Tick(0, 1'000'000, 0, false);
  ASSERT_TRUE(loop.state().second_tool.has_value());
  EXPECT_EQ(loop.last_snapshot().has_second_tool, 1);
  EXPECT_EQ(loop.last_snapshot().second.gripper, 1);
  // The two-handed tick allocates nothing after warm-up (the ring fills and counts drops).
  for (int k = 1; k < 200; ++k) loop.Tick(k * 1'000'000LL, 1'000'000, 0, false);
  testing::StartCountingAllocations();
  for (int k = 200; k < 1200; ++k) loop.Tick(k * 1'000'000LL, 1'000'000, 0, false);
  EXPECT_EQ(testing::StopCountingAllocations(), 0u);
}

}  // namespace
}  // namespace microdex::station
