// Knot tying in simulation (thesis §5.5, Fig. 5.7): a scripted bimanual trajectory of two
// grasped nodes ties a double overhand knot, and, on another thread, an overhand knot and then
// a second throw of the opposite (square) or the same (granny) handedness, and a double throw
// then a single one of the other hand (surgeon's knot), each pulled tight.
// After each stage the thread's polyline is classified by the knot recogniser, and through the
// whole run no two non-adjacent links come closer than half a thread diameter.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "common/geometry/segment_distance.h"
#include "common/knot/recognition.h"
#include "tests/support/thread_scenarios.h"

namespace microdex::thread {
namespace {

using geometry::ClosestSegmentSegment;
using geometry::SegmentClosest;
using knot::AnalyzeKnot;
using knot::KnotAnalysis;
using knot::KnotOptions;
using knot::KnotType;
using knot::RecognizeKnot;

// Brute-force smallest centreline distance between non-adjacent links, over all pairs closer
// than limit_m (a pair's bounding spheres prune the exact segment test); limit_m if none is.
// Independent of the simulation's own sphere hierarchy.
double MinNonAdjacentDistanceBelow(const Eigen::Matrix3Xd& x, double limit_m) {
  const int links = static_cast<int>(x.cols()) - 1;
  std::vector<Eigen::Vector3d> mid(links);
  std::vector<double> half(links);
  for (int j = 0; j < links; ++j) {
    mid[j] = 0.5 * (x.col(j) + x.col(j + 1));
    half[j] = 0.5 * (x.col(j + 1) - x.col(j)).norm();
  }
  double best = limit_m;
  for (int a = 0; a < links; ++a) {
    for (int b = a + 2; b < links; ++b) {
      const double reach = half[a] + half[b] + best;
      if ((mid[a] - mid[b]).squaredNorm() >= reach * reach) continue;
      const SegmentClosest c =
          ClosestSegmentSegment(x.col(a), x.col(a + 1), x.col(b), x.col(b + 1));
      best = std::min(best, c.distance_m);
    }
  }
  return best;
}

KnotType Recognize(const ThreadModel& model, const ThreadState& state) {
  std::vector<Eigen::Vector3d> poly(model.num_nodes);
  for (int i = 0; i < model.num_nodes; ++i) poly[i] = state.x_W.col(i);
  KnotOptions options;
  options.thread_diameter_m = model.def.diameter_m;
  options.locate = false;
  return RecognizeKnot(poly, options);
}

double KnotCentreX(const ThreadModel& model, const ThreadState& state) {
  std::vector<Eigen::Vector3d> poly(model.num_nodes);
  for (int i = 0; i < model.num_nodes; ++i) poly[i] = state.x_W.col(i);
  KnotOptions options;
  options.thread_diameter_m = model.def.diameter_m;
  const KnotAnalysis a = AnalyzeKnot(poly, options);
  EXPECT_TRUE(a.located);
  return a.p_core_W.x();
}

struct ThrowResult {
  double min_distance_m = std::numeric_limits<double>::infinity();
  long long trouble = 0;  // rolled-back steps
  bool finite = true;
  double pull_force_N = 0.0;  // the smaller grasp force at the end of the pull
  // Largest grasp forces while the driver draws the end out of the throw (exit phase).
  double exit_driver_N = 0.0;
  double exit_standing_N = 0.0;
};

// Runs one throw to its end, checking the non-adjacent distance after every step.
ThrowResult Tie(const ThreadModel& model, ThreadState& state, KnotTyingHands hands,
                const KnotThrowOptions& options) {
  KnotThrowScript script(model, state, hands, options);
  ThrowResult r;
  const long long before = state.status.nonfinite_resets + state.status.factorization_failures;
  const double limit = model.def.diameter_m;
  while (script.Step(model, state)) {
    if (script.phase() == KnotThrowScript::Phase::kExit) {
      r.exit_driver_N = std::max(r.exit_driver_N, state.grasps[hands.driver_slot].f_T_W.norm());
      r.exit_standing_N =
          std::max(r.exit_standing_N, state.grasps[hands.standing_slot].f_T_W.norm());
    }
    r.min_distance_m = std::min(r.min_distance_m, MinNonAdjacentDistanceBelow(state.x_W, limit));
    r.finite = r.finite && state.x_W.allFinite() && state.v_W.allFinite();
  }
  r.min_distance_m = std::min(r.min_distance_m, MinNonAdjacentDistanceBelow(state.x_W, limit));
  r.trouble = state.status.nonfinite_resets + state.status.factorization_failures - before;
  r.pull_force_N = std::min(state.grasps[hands.standing_slot].f_T_W.norm(),
                            state.grasps[hands.driver_slot].f_T_W.norm());
  return r;
}

TEST(KnotTying, DoubleOverhandPulledTight) {
  const ThreadModel model = MakeThreadModel(KnotTyingDef(257));
  ThreadState state =
      MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  const KnotTyingHands hands = SetUpKnotTying(model, state);
  ASSERT_EQ(Recognize(model, state), KnotType::kNone);
  KnotThrowOptions options;
  options.passes = 2;
  const ThrowResult r = Tie(model, state, hands, options);
  EXPECT_EQ(Recognize(model, state), KnotType::kDoubleOverhand);
  EXPECT_GE(r.pull_force_N, options.pull_tension_N);  // pulled tight, not stopped by distance
  EXPECT_GE(r.min_distance_m, 0.5 * model.def.diameter_m);
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(r.trouble, 0);
  EXPECT_LT(state.status.max_strain, 0.1);
}

// Two throws on one thread: the second is tied by the other hand (its end has the long tail),
// next to the first knot. Opposite handedness: square knot; the same: granny.
// first_passes 2 (a double throw) then a single throw of the other hand: surgeon's knot.
void TieTwoThrows(int first_passes, bool second_right, KnotType expected_first, KnotType expected) {
  const ThreadModel model = MakeThreadModel(KnotTyingDef(385));
  ThreadState state =
      MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  KnotTyingHands hands = SetUpKnotTying(model, state);
  KnotThrowOptions first;
  first.passes = first_passes;
  first.right = true;
  const ThrowResult r1 = Tie(model, state, hands, first);
  EXPECT_EQ(Recognize(model, state), expected_first);
  EXPECT_GE(r1.pull_force_N, first.pull_tension_N);

  std::swap(hands.standing_slot, hands.driver_slot);
  KnotThrowOptions second;
  second.passes = 1;
  second.right = second_right;
  second.hold_tension_N = HoldTensionAfterThrow(first, second);
  const double x1 = KnotCentreX(model, state);
  // The driver now holds node 0, left of the first knot: the second throw goes 3 mm left.
  ASSERT_LT(state.grasps[hands.driver_slot].p_WT.x(), x1);
  second.knot_x_m = x1 - 3e-3;
  const ThrowResult r2 = Tie(model, state, hands, second);
  EXPECT_EQ(Recognize(model, state), expected);
  // Drawing the end out of the second throw past the first knot: contact friction can make the
  // driver's pull at most the capstan factor exp(mu theta) times the standing hand's, theta the
  // throw's wrap of thread on thread (1.5 turns, 3 pi). An anchoring contact model (per-node
  // stiffness bounds) drags the whole knot and exceeds it several times over.
  const double capstan = std::exp(model.def.friction_coefficient * 3.0 * std::numbers::pi);
  EXPECT_GT(r2.exit_standing_N, 0.0);
  EXPECT_LE(r2.exit_driver_N, capstan * r2.exit_standing_N);
  EXPECT_GE(r2.pull_force_N, second.pull_tension_N);
  EXPECT_GE(std::min(r1.min_distance_m, r2.min_distance_m), 0.5 * model.def.diameter_m);
  EXPECT_TRUE(r1.finite && r2.finite);
  EXPECT_EQ(r1.trouble + r2.trouble, 0);
}

TEST(KnotTying, OverhandThenOppositeThrowIsSquare) {
  TieTwoThrows(1, false, KnotType::kOverhandRight, KnotType::kSquare);
}

TEST(KnotTying, OverhandThenSameThrowIsGranny) {
  TieTwoThrows(1, true, KnotType::kOverhandRight, KnotType::kGranny);
}

TEST(KnotTying, DoubleThenOppositeSingleIsSurgeons) {
  TieTwoThrows(2, false, KnotType::kDoubleOverhand, KnotType::kSurgeons);
}

}  // namespace
}  // namespace microdex::thread
