// Cue generators: the tremor band filter passes 8–12 Hz and rejects slow motion and ramps;
// the path field is the spring of its definition, towards or away from the circle, saturated.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/cues/path_force_field.h"
#include "common/cues/tremor_filter.h"

namespace microdex::cues {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Steady-state amplitude gain of the filter at f_hz, measured on a simulated sinusoid.
double Gain(double f_hz) {
  TremorFilterDef def;
  const TremorFilterModel m = MakeTremorFilter(def);
  TremorFilterState s;
  double peak = 0;
  const int n = 6000;
  for (int k = 0; k < n; ++k) {
    const double x = std::sin(2 * kPi * f_hz * k / def.sample_rate_hz);
    const Eigen::Vector3d y = StepTremorFilter(m, Eigen::Vector3d(x, 0, 0), s);
    if (k > n / 2) peak = std::max(peak, std::abs(y.x()));
  }
  return peak;
}

TEST(TremorFilter, PassesTheTremorBand) {
  for (double f : {8.0, 10.0, 12.0}) {
    EXPECT_GT(Gain(f), 0.75) << f;
    EXPECT_LT(Gain(f), 1.05) << f;
  }
  EXPECT_LT(Gain(0.25), 0.01);  // the intended motion of a pass
  EXPECT_LT(Gain(60.0), 0.15);
}

TEST(TremorFilter, RampAndConstantLeaveNoOffset) {
  TremorFilterDef def;
  const TremorFilterModel m = MakeTremorFilter(def);
  TremorFilterState s;
  Eigen::Vector3d y;
  // A constant start gives exactly zero output (steady-state initialisation).
  y = StepTremorFilter(m, Eigen::Vector3d(1e-3, 2e-3, 3e-3), s);
  EXPECT_LT(y.norm(), 1e-18);
  for (int k = 0; k < 3000; ++k) {
    y = StepTremorFilter(m, Eigen::Vector3d(1e-3 + 5e-3 * k / 1000.0, 2e-3, 3e-3), s);
  }
  EXPECT_LT(y.norm(), 1e-9) << "a 5 mm/s ramp left an offset";
  EXPECT_NO_THROW(def.Validate());
  def.low_pass_hz = 600;
  try {
    def.Validate();
    ADD_FAILURE() << "a low-pass above Nyquist was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("low_pass_hz: ", 0), 0u) << e.what();
  }
  EXPECT_THROW(MakeTremorFilter(def), std::invalid_argument);
}

TEST(PathField, SpringTowardsOrAwayFromTheCircle) {
  PathCircle c;
  c.X_WC.translation() = Eigen::Vector3d(1e-3, 0, 0);
  c.radius_m = 5e-3;
  const Eigen::Vector3d p(1e-3 + 5.2e-3, 0, 0.1e-3);  // 0.2 mm out, 0.1 mm up
  const Eigen::Vector3d e(0.2e-3, 0, 0.1e-3);
  const Eigen::Vector3d conv = CalcPathFieldForce(c, p, 300, 10);
  const Eigen::Vector3d div = CalcPathFieldForce(c, p, -300, 10);
  EXPECT_LT((conv + 300 * e).norm(), 1e-12);
  EXPECT_LT((div - 300 * e).norm(), 1e-12);
  const Eigen::Vector3d sat = CalcPathFieldForce(c, p, 1e6, 0.05);
  EXPECT_NEAR(sat.norm(), 0.05, 1e-12);
  EXPECT_GT(sat.normalized().dot(conv.normalized()), 1 - 1e-12);
  // On the axis there is no nearest point and no force.
  EXPECT_EQ(CalcPathFieldForce(c, Eigen::Vector3d(1e-3, 0, 2e-3), 300, 10),
            Eigen::Vector3d::Zero());
  // On the circle, no force.
  EXPECT_LT(CalcPathFieldForce(c, Eigen::Vector3d(1e-3, 5e-3, 0), 300, 10).norm(), 1e-15);
}

TEST(PathField, SegmentSpringTowardsTheNearestPointOfTheSegment) {
  IdealPath path;
  path.is_segment = true;
  path.segment = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.01, 0, 0)};
  // Beside the middle: the nearest point is the foot of the perpendicular.
  const Eigen::Vector3d p(4e-3, 0.3e-3, -0.4e-3);
  EXPECT_LT((CalcNearestOnSegment(path.segment, p) - Eigen::Vector3d(4e-3, 0, 0)).norm(), 1e-18);
  EXPECT_LT(
      (CalcPathFieldForce(path, p, 200, 10) + 200 * Eigen::Vector3d(0, 0.3e-3, -0.4e-3)).norm(),
      1e-12);
  EXPECT_LT(
      (CalcPathFieldForce(path, p, -200, 10) - 200 * Eigen::Vector3d(0, 0.3e-3, -0.4e-3)).norm(),
      1e-12);
  // Beyond either end: the end point.
  EXPECT_EQ(CalcNearestOnSegment(path.segment, Eigen::Vector3d(-1e-3, 1e-3, 0)), path.segment.a_W);
  EXPECT_EQ(CalcNearestOnSegment(path.segment, Eigen::Vector3d(2e-2, 1e-3, 0)), path.segment.b_W);
  EXPECT_NEAR(CalcPathFieldForce(path, Eigen::Vector3d(0.05, 0, 0), 1e4, 0.3).norm(), 0.3, 1e-12);
  // A degenerate segment is its point.
  path.segment.b_W = path.segment.a_W;
  EXPECT_EQ(CalcNearestOnSegment(path.segment, p), path.segment.a_W);
}

}  // namespace
}  // namespace microdex::cues
