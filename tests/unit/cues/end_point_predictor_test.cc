// The end-point predictor: the minimum-jerk phase inverts its ratio v² / (a d) exactly; on a clean
// minimum-jerk reach the predicted end point converges to the true one; on the seeded scripted
// reaches (tests/support/reach_scripts.h) the warning comes >= 150 ms before the error in
// >= 80 % of erring reaches with <= 10 % false alarms.
#include "common/cues/end_point_predictor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "tests/support/reach_scripts.h"

namespace microdex::cues {
namespace {

TEST(EndPointPredictor, PhaseInvertsTheMinimumJerkRatio) {
  for (double tau = 0.05; tau < 0.99; tau += 0.01) {
    const double s = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
    const double ds = 30 * tau * tau * (1 - tau) * (1 - tau);
    const double dds = 60 * tau * (1 - tau) * (1 - 2 * tau);
    if (std::abs(dds) < 1e-6) continue;  // the peak speed: q is ±∞
    EXPECT_NEAR(CalcMinimumJerkPhaseFromAcceleration(ds * ds / (dds * s)), tau, 1e-9) << tau;
  }
  EXPECT_EQ(CalcMinimumJerkPhaseFromAcceleration(1.2), 0.0);
  EXPECT_EQ(CalcMinimumJerkPhaseFromAcceleration(std::nan("")), 0.0);
}

TEST(EndPointPredictor, CleanReachConvergesOnItsEndPoint) {
  testing::ReachSetDef def;
  def.tremor_min_m = def.tremor_max_m = 0;
  def.noise_m = 0;
  testing::Reach r;
  r.start = Eigen::Vector3d(1e-3, 2e-3, 0);
  r.end = r.target = Eigen::Vector3d(6e-3, -1e-3, 0);
  r.duration_s = 0.8;
  int start = 0;
  const auto p = testing::SampleReach(def, r, 0.3, 1, &start);
  const EndPointPredictorModel model = MakeEndPointPredictor({});
  EndPointPredictorState s;
  double worst_late_error = 0;
  int valid = 0;
  for (int i = 0; i < static_cast<int>(p.size()); ++i) {
    const EndPointPrediction e = StepEndPointPredictor(model, p[i], s);
    if (!e.valid) continue;
    ++valid;
    // From 60 % of the reach on, within 10 % of its length of the true end.
    if (i > start + 0.6 * 800)
      worst_late_error = std::max(worst_late_error, (e.p_W_end - r.end).norm());
  }
  EXPECT_GT(valid, 200);
  EXPECT_LT(worst_late_error, 0.1 * (r.end - r.start).norm());
}

TEST(EndPointPredictor, NonFiniteInputRestartsAndDefsValidate) {
  const EndPointPredictorModel model = MakeEndPointPredictor({});
  EndPointPredictorState s;
  StepEndPointPredictor(model, Eigen::Vector3d(1, 2, 3), s);
  const EndPointPrediction e = StepEndPointPredictor(model, Eigen::Vector3d(std::nan(""), 0, 0), s);
  EXPECT_FALSE(e.valid);
  EXPECT_EQ(s.started, 0);
  EndPointPredictorDef bad;
  bad.smoothing_hz = 900;
  EXPECT_THROW(MakeEndPointPredictor(bad), std::invalid_argument);
}

TEST(EndPointPredictor, WarnsEarlyOnErringReachesWithFewFalseAlarms) {
  testing::ReachSetDef def;
  def.reaches = 60;
  for (std::uint64_t seed : {1u, 2u}) {
    def.seed = seed;
    const testing::PredictiveReport r = testing::EvaluatePredictive(def);
    SCOPED_TRACE(::testing::Message()
                 << "seed " << seed << ": lead median " << r.lead_ms_median << " ms, hit rate "
                 << r.hit_rate << ", false alarms " << r.false_alarm_rate);
    ASSERT_GT(r.erring, 10);
    ASSERT_GT(r.correct, 10);
    EXPECT_GE(r.hit_rate, 0.8);
    EXPECT_LE(r.false_alarm_rate, 0.1);
    EXPECT_GE(r.lead_ms_median, 150);
  }
}

}  // namespace
}  // namespace microdex::cues
