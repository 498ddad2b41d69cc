// Period statistics against a sort of the same samples, and the score formula at its corners.
#include "station/period_stats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "station/score.h"

namespace microdex::station {
namespace {

TEST(PeriodStats, QuantilesMatchSortedSamples) {
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(1e6, 3e4);
  std::vector<std::int64_t> v;
  PeriodStats stats;
  for (int i = 0; i < 20000; ++i) {
    std::int64_t p = static_cast<std::int64_t>(jitter(rng));
    if (i % 997 == 0) p = 25'000'000 + i;  // beyond the histogram: kept exactly
    v.push_back(p);
    stats.Add(p);
  }
  std::sort(v.begin(), v.end());
  for (double q : {0.5, 0.99, 0.999, 0.9995}) {
    const std::int64_t ref = v[static_cast<std::size_t>(std::ceil(q * v.size())) - 1];
    const double got = stats.Quantile_s(q);
    if (ref < PeriodStats::kBins * PeriodStats::kBin_ns) {
      // Histogram: the upper edge of the 1 µs bin holding the reference.
      EXPECT_EQ(static_cast<std::int64_t>(std::llround(got * 1e9)),
                (ref / PeriodStats::kBin_ns + 1) * PeriodStats::kBin_ns)
          << q;
    } else {
      EXPECT_EQ(static_cast<std::int64_t>(std::llround(got * 1e9)), ref) << q;
    }
  }
  EXPECT_DOUBLE_EQ(stats.max_s(), static_cast<double>(v.back()) * 1e-9);
  EXPECT_EQ(stats.count(), 20000u);
  stats.Reset();
  EXPECT_EQ(stats.count(), 0u);
  EXPECT_EQ(stats.Quantile_s(0.99), 0);
}

TEST(Score, Corners) {
  scene::SceneModel scene;
  scene.modules = {"needle", "tremor"};
  scene.vessel.tube_radius_m = 0.5e-3;
  state::ScoreState t;
  t.time_s = 10;
  t.clearance_samples = 100;
  t.clearance_sum_m = 100 * 0.5e-3;  // always on the core circle
  t.min_clearance_m = 0.5e-3;
  EXPECT_NEAR(CalcScore(scene, t).score, 100, 1e-9);
  t.clearance_sum_m = 0;  // riding the wall, never touching
  EXPECT_NEAR(CalcScore(scene, t).score, 50, 1e-9);
  t.time_in_contact_s = 5;  // half the time in contact
  EXPECT_NEAR(CalcScore(scene, t).score, 25, 1e-9);
  t.clearance_samples = 0;
  EXPECT_EQ(CalcScore(scene, t).score, 0);
  EXPECT_TRUE(std::isnan(CalcScore(scene, t).mean_clearance_m));
  // Without the needle, the share of the time without fault (no clearance needed).
  scene.modules = {"thread", "tissue"};
  EXPECT_NEAR(CalcScore(scene, t).score, 50, 1e-9);
  t.time_in_contact_s = 0;
  EXPECT_NEAR(CalcScore(scene, t).score, 100, 1e-9);
  t.time_in_contact_s = 10;
  EXPECT_NEAR(CalcScore(scene, t).score, 0, 1e-9);
}

}  // namespace
}  // namespace microdex::station
