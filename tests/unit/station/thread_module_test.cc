// The station's thread module against Hooke's law: the thread anchored at one end and pulled
// straight by the tool to a strain ε pulls back on the tool with E A ε towards the anchor
// (every link carries the same tension), its largest link strain is ε, a slack thread pulls
// with (almost) nothing, and a strain beyond the scene's limit is a fault. The module's frame
// carries the nodes at the mirror period.
#include "station/thread_module.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>

namespace microdex::station {
namespace {

std::string SceneDir() {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes";
}

scene::SceneModel ThreadScene() {
  return scene::ParseScene(R"(
name: test-thread
modules: [thread]
thread:
  params: thread_stiff_nylon_10_0.yaml
  anchor_m: [0.001, 0.002, 0.003]
  max_strain: 0.03
task: {path: line, line_start_m: [0.031, 0.002, 0.003], line_end_m: [0.032, 0.002, 0.003]}
haptic: {rate_hz: 1000, max_force_N: 2.0}
)",
                           SceneDir() + "/inline.yaml");
}

// Moves the grasped end from the thread's rest position to p_end in `ramp` steps, then holds
// it for `hold` steps; returns the rendered force of the last step.
Eigen::Vector3d PullTo(ThreadModule& m, state::StationState& s, const Eigen::Vector3d& p_start,
                       const Eigen::Vector3d& p_end, int ramp, int hold) {
  ToolInput in;
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  for (int k = 0; k < ramp + hold; ++k) {
    const double u = std::min(1.0, static_cast<double>(k + 1) / ramp);
    in.step = static_cast<std::uint64_t>(k);
    in.X_WT = Eigen::Isometry3d::Identity();
    in.X_WT.translation() = p_start + u * (p_end - p_start);
    f.setZero();
    m.Step(in, s, f);
  }
  return f;
}

TEST(ThreadModule, PulledStraightItPullsBackWithHookesTension) {
  const scene::SceneModel scene = ThreadScene();
  const thread::ThreadDef& def = scene.thread->def;
  const Eigen::Vector3d anchor = scene.thread->p_W_anchor;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const double length_m = def.length_m;
  // Independent reference: a uniform bar, tension E A ε.
  const double area_m2 = std::numbers::pi * def.diameter_m * def.diameter_m / 4;
  for (double strain : {0.005, 0.02}) {
    ThreadModule pulled(scene);
    state::StationState s;
    pulled.InitState(s);
    const Eigen::Vector3d f =
        PullTo(pulled, s, anchor + length_m * x, anchor + length_m * (1 + strain) * x, 300, 700);
    const double tension_N = def.youngs_modulus_Pa * area_m2 * strain;
    // Towards the anchor (−x), magnitude E A ε; the linear stretch law is exact for a
    // straight uniform chain, the rest is gravity on 2.6e-10 kg nodes (1e-8 of the force).
    EXPECT_NEAR(f.x(), -tension_N, 0.01 * tension_N) << "strain " << strain;
    EXPECT_NEAR(f.y(), 0, 1e-3 * tension_N);
    EXPECT_NEAR(f.z(), 0, 1e-3 * tension_N);
    EXPECT_NEAR(pulled.Status(s).error_estimate, strain, 0.02 * strain);
    EXPECT_EQ(pulled.Status(s).fault, strain > scene.thread->max_strain);
    // The anchored node has not moved.
    EXPECT_LT((s.thread->thread.x_W.col(0) - anchor).norm(), 1e-12);
  }
}

TEST(ThreadModule, SlackThreadPullsWithAlmostNothing) {
  const scene::SceneModel scene = ThreadScene();
  ThreadModule m(scene);
  state::StationState s;
  m.InitState(s);
  const Eigen::Vector3d anchor = scene.thread->p_W_anchor;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const double length_m = scene.thread->def.length_m;
  const Eigen::Vector3d f =
      PullTo(m, s, anchor + length_m * x, anchor + 0.9 * length_m * x, 300, 700);
  // 10 % slack: only bending of the buckled nylon (κ_b ~ 1e-7 N m over mm) and its weight.
  EXPECT_LT(f.norm(), 1e-3);
  EXPECT_FALSE(m.Status(s).fault);
  EXPECT_EQ(m.Status(s).warnings, 0u);
}

TEST(ThreadModule, OverstretchIsAFaultAndTheForceStaysSaturated) {
  const scene::SceneModel scene = ThreadScene();
  ThreadModule m(scene);
  state::StationState s;
  m.InitState(s);
  const Eigen::Vector3d anchor = scene.thread->p_W_anchor;
  const double length_m = scene.thread->def.length_m;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  // 30 % strain would be 0.44 N; 200 % is far beyond the 2 N saturation.
  const Eigen::Vector3d f =
      PullTo(m, s, anchor + length_m * x, anchor + 3 * length_m * x, 500, 100);
  EXPECT_TRUE(f.allFinite());
  EXPECT_LE(f.norm(), scene.haptic.max_force_N * (1 + 1e-12));
  EXPECT_TRUE(m.Status(s).fault);
}

TEST(ThreadModule, FrameCarriesTheNodes) {
  const scene::SceneModel scene = ThreadScene();
  ThreadModule m(scene);
  state::StationState s;
  m.InitState(s);
  auto frames = std::make_unique<LargeFrames>();
  EXPECT_FALSE(frames->thread.Update());
  const Eigen::Vector3d anchor = scene.thread->p_W_anchor;
  PullTo(m, s, anchor + 0.03 * Eigen::Vector3d::UnitX(), Eigen::Vector3d(0.02, 0.01, 0.004), 50,
         10);
  m.WriteFrame(s, 60, 1234, *frames);
  ASSERT_TRUE(frames->thread.Update());
  const ThreadFrame& f = frames->thread.front();
  EXPECT_EQ(f.step, 60u);
  EXPECT_EQ(f.stamp_ns, 1234);
  ASSERT_EQ(f.num_nodes, scene.thread->def.num_nodes);
  for (int i = 0; i < f.num_nodes; ++i) {
    for (int a = 0; a < 3; ++a) EXPECT_EQ(f.p_W[i][a], s.thread->thread.x_W(a, i));
  }
  EXPECT_EQ(f.grasped_node, f.num_nodes - 1);
  EXPECT_EQ(f.max_strain, m.Status(s).error_estimate);
  EXPECT_EQ(f.f_T_W[0], s.thread->f_T_W.x());
}

TEST(ThreadModule, SlackThreadStartsAsAnArcOfRestLengthLinks) {
  const Eigen::Vector3d a(0.001, -0.002, 0.0005), b(0.021, 0.004, -0.001);
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ();
  for (double length_m :
       {(b - a).norm(), 1.02 * (b - a).norm(), 1.5 * (b - a).norm(), 3.0 * (b - a).norm()}) {
    const int n = 65;
    const Eigen::Matrix3Xd x = CalcSlackThreadNodes(a, b, side, length_m, n);
    EXPECT_LT((x.col(0) - a).norm(), 1e-15);
    EXPECT_LT((x.col(n - 1) - b).norm(), 1e-15);
    // Equal chords of an arc of length L: each chord is 2R sin(θ / (n − 1)), just under the
    // rest length L / (n − 1): relative gap about θ² / (6 (n − 1)²) < π² / (6 · 64²) = 4.0e-4.
    const double rest_m = length_m / (n - 1);
    double sum_m = 0;
    for (int i = 0; i + 1 < n; ++i) {
      const double l = (x.col(i + 1) - x.col(i)).norm();
      EXPECT_LE(l, rest_m * (1 + 1e-12)) << "L " << length_m << " link " << i;
      EXPECT_GE(l, rest_m * (1 - 4.1e-4)) << "L " << length_m << " link " << i;
      sum_m += l;
    }
    EXPECT_NEAR(sum_m, length_m, 4.1e-4 * length_m);
    // The middle bows towards +z (above the chord's midpoint) unless taut.
    const double bow_m = (x.col(n / 2) - 0.5 * (a + b)).dot(side);
    if (length_m > (b - a).norm() * (1 + 1e-9)) {
      EXPECT_GT(bow_m, 0);
    } else {
      EXPECT_NEAR(bow_m, 0, 1e-15);
    }
  }
}

TEST(ThreadModule, ThreadBeyondThePublishedBoundIsRefused) {
  scene::SceneModel scene = ThreadScene();
  scene.thread->def.num_nodes = static_cast<int>(kMaxFrameThreadNodes) + 1;
  try {
    ThreadModule m(scene);
    FAIL() << "a thread of more than kMaxThreadNodes nodes was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("num_nodes"), std::string::npos) << e.what();
  }
}

}  // namespace
// The nylon-control shape error: zero for a rigidly moved copy (any rotation, translation), the
// offset's RMS for a deformed one, and no reflection (a mirror image is not the same shape).
TEST(ThreadModule, AlignedRmsDistanceIsRigidMotionInvariant) {
  Eigen::Matrix3Xd target(3, 40);
  for (int i = 0; i < 40; ++i) {
    const double s = 0.2 * i;
    target.col(i) = Eigen::Vector3d(std::cos(s), std::sin(2 * s), 0.3 * s) * 1e-3;
  }
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3Xd moved = (R * target).colwise() + Eigen::Vector3d(5e-3, -2e-3, 1e-3);
  EXPECT_NEAR(CalcAlignedRmsDistance(moved, target), 0, 1e-15);
  // Stretch one axis by 10 %: the best alignment leaves a positive error, below the RMS of the
  // stretch itself (the alignment can only help).
  Eigen::Matrix3Xd stretched = target;
  stretched.row(2) *= 1.1;
  const double e = CalcAlignedRmsDistance(stretched, target);
  const Eigen::Vector3d c = target.rowwise().mean();
  double sq = 0;
  for (int i = 0; i < 40; ++i) sq += std::pow(0.1 * (target(2, i) - c.z()), 2);
  EXPECT_GT(e, 0);
  EXPECT_LE(e, std::sqrt(sq / 40) + 1e-15);
  // A mirror image is not reached by a rotation.
  Eigen::Matrix3Xd mirrored = target;
  mirrored.row(1) *= -1;
  EXPECT_GT(CalcAlignedRmsDistance(mirrored, target), 1e-4);
}

}  // namespace microdex::station
