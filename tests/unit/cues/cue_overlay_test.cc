// Visual cues as overlay data: the path polyline lies on the path, the limits at the given
// offset, the deviation joins the tool to its nearest path point with a colour that goes from
// green to red as the deviation grows, the clearance colour likewise as the clearance falls.
#include "common/cues/cue_overlay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace microdex::cues {
namespace {

constexpr double kTol_m = 1e-9;

OverlayInput CircleInput() {
  OverlayInput in;
  in.path.circle.radius_m = 5e-3;
  in.tolerance_m = 0.5e-3;
  in.p_WT = Eigen::Vector3d(5.3e-3, 0, 0);
  in.p_W_nearest = Eigen::Vector3d(5e-3, 0, 0);
  in.deviation_m = 0.3e-3;
  in.clearance_m = 0.2e-3;
  return in;
}

TEST(CueOverlay, EmptyWhenNoVisualCueIsOn) {
  CueOverlay o;
  OverlayInput in = CircleInput();
  in.active = CueBit(CueKind::kConvergentField) | CueBit(CueKind::kAudioClick);
  CalcCueOverlay(in, o);
  EXPECT_EQ(o.polyline_count, 0);
  EXPECT_EQ(o.label_count, 0);
}

TEST(CueOverlay, PathAndLimitsLieWhereTheyShould) {
  OverlayInput in = CircleInput();
  in.active = CueBit(CueKind::kVisualPath) | CueBit(CueKind::kVisualLimits);
  in.param[static_cast<std::size_t>(CueKind::kVisualLimits)] = 0;  // the task's tolerance
  CueOverlay o;
  CalcCueOverlay(in, o);
  ASSERT_EQ(o.polyline_count, 3);
  EXPECT_EQ(o.polylines[0].role, OverlayRole::kPath);
  const double expected_r[] = {5e-3, 5.5e-3, 4.5e-3};
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(o.polylines[i].count, kMaxOverlayPoints);
    for (int k = 0; k < o.polylines[i].count; ++k) {
      const Eigen::Vector3d& p = o.polylines[i].p_W[k];
      EXPECT_NEAR(std::hypot(p.x(), p.y()), expected_r[i], kTol_m);
      EXPECT_NEAR(p.z(), 0, kTol_m);
    }
  }
  // A segment path: its two ends, and the limits offset across it.
  in.path.is_segment = true;
  in.path.segment = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.01, 0, 0)};
  in.param[static_cast<std::size_t>(CueKind::kVisualLimits)] = 1e-3;
  CalcCueOverlay(in, o);
  ASSERT_EQ(o.polyline_count, 3);
  EXPECT_EQ(o.polylines[0].count, 2);
  EXPECT_NEAR(std::abs(o.polylines[1].p_W[0].y()), 1e-3, kTol_m);
  EXPECT_NEAR(o.polylines[1].p_W[0].y(), -o.polylines[2].p_W[0].y(), kTol_m);
}

TEST(CueOverlay, DeviationAndClearanceColoursFollowTheirGradients) {
  OverlayInput in = CircleInput();
  in.active = CueBit(CueKind::kVisualDeviation);
  CueOverlay o;
  double prev_red = -2;
  for (double dev : {0.0, 0.1e-3, 0.25e-3, 0.4e-3, 0.5e-3}) {
    in.deviation_m = dev;
    CalcCueOverlay(in, o);
    ASSERT_EQ(o.polyline_count, 1);
    const OverlayPolyline& p = o.polylines[0];
    EXPECT_EQ(p.role, OverlayRole::kDeviation);
    EXPECT_EQ(p.p_W[0], in.p_WT);
    EXPECT_EQ(p.p_W[1], in.p_W_nearest);
    // Red minus green grows with the deviation.
    const double red = p.colour.r - p.colour.g;
    EXPECT_GT(red, prev_red);
    prev_red = red;
    ASSERT_EQ(o.label_count, 1);
    char expected[32];
    std::snprintf(expected, sizeof expected, "%.3f mm", dev * 1e3);
    EXPECT_EQ(std::string(o.labels[0].text.data()), expected);
  }
  EXPECT_EQ(o.polylines[0].colour.g, 0.0f) << "full red at the full-scale deviation";
  in.active = CueBit(CueKind::kVisualClearance);
  in.param[static_cast<std::size_t>(CueKind::kVisualClearance)] = 1e-3;
  in.has_wall_points = true;
  in.p_W_tool_near = Eigen::Vector3d(1, 2, 3);
  in.p_W_wall = Eigen::Vector3d(1, 2, 4);
  double prev = -2;
  for (double c : {1.5e-3, 0.8e-3, 0.4e-3, 0.1e-3, -0.1e-3}) {
    in.clearance_m = c;
    CalcCueOverlay(in, o);
    ASSERT_EQ(o.polyline_count, 1);
    EXPECT_EQ(o.polylines[0].p_W[1], in.p_W_wall);
    const double red = o.polylines[0].colour.r - o.polylines[0].colour.g;
    EXPECT_GE(red, prev);
    prev = red;
  }
  EXPECT_EQ(CalcGradientColour(0).r, 0.0f);
  EXPECT_EQ(CalcGradientColour(1).g, 0.0f);
  EXPECT_EQ(CalcGradientColour(std::nan("")).r, 0.5f);
}

TEST(CueOverlay, PredictionTurnsRedOnAWarning) {
  OverlayInput in = CircleInput();
  in.active = CueBit(CueKind::kPredictive);
  CueOverlay o;
  CalcCueOverlay(in, o);
  EXPECT_EQ(o.polyline_count, 0) << "no prediction, nothing drawn";
  in.prediction_valid = true;
  in.p_W_end = Eigen::Vector3d(6e-3, 1e-3, 0);
  CalcCueOverlay(in, o);
  ASSERT_EQ(o.polyline_count, 1);
  EXPECT_LT(o.polylines[0].colour.r, 0.5f);
  in.warning = true;
  CalcCueOverlay(in, o);
  EXPECT_EQ(o.polylines[0].colour.r, 1.0f);
  EXPECT_EQ(o.polylines[0].colour.g, 0.0f);
  EXPECT_EQ(o.polylines[0].p_W[1], in.p_W_end);
}

}  // namespace
}  // namespace microdex::cues
