// The force limiter: finite, saturated and rate-limited whatever it is asked; and a sampled
// spring far too stiff for the device (1e6 N/m on a 50 g handle at 1 kHz) stays bounded
// behind it, while the same spring without it diverges.
#include "common/cues/force_limits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/cues/path_force_field.h"

namespace microdex::cues {
namespace {

constexpr double kDt_s = 1e-3;
constexpr double kMaxForce_N = 2;

TEST(ForceLimits, FiniteSaturatedAndRateLimited) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  ForceLimitResult r = LimitForce(Eigen::Vector3d(nan, 0, 0), Eigen::Vector3d(0.5, 0, 0),
                                  kMaxForce_N, kMaxForceRate_N_per_s, kDt_s);
  EXPECT_TRUE(r.non_finite);
  EXPECT_EQ(r.f_N, Eigen::Vector3d(0.5, 0, 0)) << "a NaN request holds the previous force";
  r = LimitForce(Eigen::Vector3d(100, 0, 0), zero, kMaxForce_N, kMaxForceRate_N_per_s, kDt_s);
  EXPECT_TRUE(r.rate_limited);
  EXPECT_NEAR(r.f_N.norm(), kMaxForceRate_N_per_s * kDt_s, 1e-12);
  Eigen::Vector3d f = zero;
  for (int i = 0; i < 10; ++i) {
    f = LimitForce(Eigen::Vector3d(0, 100, 0), f, kMaxForce_N, kMaxForceRate_N_per_s, kDt_s).f_N;
  }
  EXPECT_NEAR(f.norm(), kMaxForce_N, 1e-12) << "saturated";
  r = LimitForce(Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0.1, 0.2, 0.2), kMaxForce_N,
                 kMaxForceRate_N_per_s, kDt_s);
  EXPECT_FALSE(r.rate_limited);
  EXPECT_EQ(r.f_N, Eigen::Vector3d(0.1, 0.2, 0.3)) << "a small change passes untouched";
  r = LimitForce(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(nan, 0, 0), kMaxForce_N,
                 kMaxForceRate_N_per_s, kDt_s);
  EXPECT_TRUE(r.f_N.allFinite());
}

// A handle of mass m with damping b, held by a hand spring k_hand at x = 1 mm from the path
// (a segment on the x-axis), under the path field of stiffness k; returns the largest
// |x| over the last half second and checks every force step.
double RunHandle(double k_N_per_m, bool divergent, bool limited, bool* steps_ok) {
  const double m = 0.05, b = 0.5, k_hand = 200, x_hand = 1e-3;
  IdealPath path;
  path.is_segment = true;
  path.segment = {Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(1, 0, 0)};
  Eigen::Vector3d p(0, x_hand, 0), v = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
  double late_max = 0;
  *steps_ok = true;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d request = divergent ? CalcDivergentFieldForce(path, p, k_N_per_m, 1e9)
                                              : CalcPathFieldForce(path, p, k_N_per_m, 1e9);
    const Eigen::Vector3d prev = f;
    f = limited ? LimitForce(request, prev, kMaxForce_N, kMaxForceRate_N_per_s, kDt_s).f_N
                : request;
    if (limited && (!(f.norm() <= kMaxForce_N + 1e-12) ||
                    !((f - prev).norm() <= kMaxForceRate_N_per_s * kDt_s + 1e-12))) {
      *steps_ok = false;
    }
    const Eigen::Vector3d hand(0, x_hand, 0);
    const Eigen::Vector3d a = (f - k_hand * (p - hand) - b * v) / m;
    v += kDt_s * a;  // semi-implicit Euler, the device's own integration
    p += kDt_s * v;
    if (!p.allFinite()) return std::numeric_limits<double>::infinity();
    if (i >= 2500) late_max = std::max(late_max, std::abs(p.y()));
  }
  return late_max;
}

TEST(ForceLimits, NoStiffnessWithinTheLimitsMakesTheDeviceUnstable) {
  for (double k : {0.0, 1.0, 200.0, 2000.0, 1e4, 1e5, 1e6}) {
    for (bool divergent : {false, true}) {
      SCOPED_TRACE(testing::Message() << "k " << k << (divergent ? " divergent" : " convergent"));
      bool ok = false;
      const double x = RunHandle(k, divergent, /*limited=*/true, &ok);
      EXPECT_TRUE(ok) << "a force step beyond the limits";
      // Bounded: no further than the saturated force can push the hand spring, 2 N / 200 N/m.
      EXPECT_LE(x, 1e-3 + kMaxForce_N / 200 + 1e-6);
    }
  }
  bool ok = false;
  EXPECT_GT(RunHandle(1e6, false, /*limited=*/false, &ok), 1.0)
      << "without the limiter the sampled 1e6 N/m spring diverges (the limiter is what holds)";
}

}  // namespace
}  // namespace microdex::cues
