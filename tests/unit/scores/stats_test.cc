// The report's statistics against values computed by hand (and R: t.test, effsize::cohen.g).

#include "common/scores/stats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace microdex::scores {
namespace {

TEST(Stats, StudentQuantiles) {
  EXPECT_NEAR(StudentT975(1), 12.7062, 1e-4);
  EXPECT_NEAR(StudentT975(4), 2.7764, 1e-4);
  EXPECT_NEAR(StudentT975(30), 2.0423, 1e-4);
  // Beyond the table: qt(0.975, 40) = 2.021075, qt(0.975, 120) = 1.979930.
  EXPECT_NEAR(StudentT975(40), 2.021075, 2e-4);
  EXPECT_NEAR(StudentT975(120), 1.979930, 1e-4);
  EXPECT_TRUE(std::isnan(StudentT975(0)));
}

TEST(Stats, MeanWithConfidenceInterval) {
  const std::vector<double> x = {2, 4, 4, 4, 5, 5, 7, 9};
  const MeanCi m = CalcMeanCi(x);
  EXPECT_EQ(m.n, 8);
  EXPECT_DOUBLE_EQ(m.mean, 5);
  EXPECT_NEAR(m.sd, std::sqrt(32.0 / 7), 1e-12);
  // mean ± t(7) sd / √8, t(7) = 2.3646.
  EXPECT_NEAR(m.hi - m.mean, 2.3646 * std::sqrt(32.0 / 7) / std::sqrt(8.0), 1e-9);
  EXPECT_NEAR(m.mean - m.lo, m.hi - m.mean, 1e-12);
  const MeanCi one = CalcMeanCi(std::vector<double>{3});
  EXPECT_EQ(one.lo, 3);
  EXPECT_TRUE(std::isnan(CalcMeanCi(std::vector<double>{}).mean));
}

TEST(Stats, HedgesG) {
  // Groups of 4: means 6 and 4, both variance 10/3, s_pooled = √(10/3), d = 2 / √(10/3) =
  // 1.095445; J = 1 − 3 / (4·8 − 9) = 20/23; g = 0.952561. var = 8/16 + g²/16 → se 0.752838.
  const std::vector<double> a = {4, 5, 7, 8}, b = {2, 3, 5, 6};
  const EffectSize e = CalcHedgesG(a, b);
  EXPECT_NEAR(e.g, 0.952561, 1e-6);
  EXPECT_NEAR(e.hi - e.g, 1.959964 * std::sqrt(0.5 + e.g * e.g / 16), 1e-6);
  EXPECT_NEAR(e.g - e.lo, e.hi - e.g, 1e-12);
  const EffectSize r = CalcHedgesG(b, a);
  EXPECT_NEAR(r.g, -e.g, 1e-12);
  EXPECT_TRUE(std::isnan(CalcHedgesG(std::vector<double>{1}, b).g));
  EXPECT_TRUE(std::isnan(CalcHedgesG(std::vector<double>{1, 1}, std::vector<double>{2, 2}).g));
}

}  // namespace
}  // namespace microdex::scores
