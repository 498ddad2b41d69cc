#include "common/geometry/quartic.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace microdex::geometry {
namespace {

// k = c·∏(t − root_i) (degree = roots.size() ≤ 4), expanded.
void FromRoots(double c, const std::vector<double>& roots, double k[5]) {
  double p[5] = {c, 0, 0, 0, 0};
  int deg = 0;
  for (const double r : roots) {
    for (int i = deg + 1; i > 0; --i) p[i] = p[i - 1] - r * p[i];
    p[0] = -r * p[0];
    ++deg;
  }
  std::copy(p, p + 5, k);
}

void ExpectRoots(const double k[5], std::vector<double> expected, double tol) {
  std::sort(expected.begin(), expected.end());
  for (const bool closed_form : {false, true}) {
    double roots[4];
    bool fallback = false;
    const int n = closed_form ? SolveQuarticInInterval(k, -1, 1, 2, {}, roots, &fallback)
                              : FindPolyRootsInInterval(k, -1, 1, {}, roots);
    ASSERT_EQ(n, static_cast<int>(expected.size())) << (closed_form ? "closed form" : "newton");
    for (int i = 0; i < n; ++i) EXPECT_NEAR(roots[i], expected[i], tol);
  }
}

TEST(QuarticTest, FourSimpleRoots) {
  double k[5];
  FromRoots(0.7, {-0.9, -0.2, 0.35, 0.8}, k);
  ExpectRoots(k, {-0.9, -0.2, 0.35, 0.8}, 1e-14);
}

TEST(QuarticTest, RootsOutsideTheIntervalAreDropped) {
  double k[5];
  FromRoots(-2.0, {-3.0, -0.5, 0.25, 7.0}, k);
  ExpectRoots(k, {-0.5, 0.25}, 1e-14);
}

TEST(QuarticTest, VanishingLeadingCoefficients) {
  double k[5];
  FromRoots(1.5, {-0.4, 0.6}, k);  // degree 2
  ExpectRoots(k, {-0.4, 0.6}, 1e-14);
  FromRoots(1.5, {0.1}, k);  // degree 1
  ExpectRoots(k, {0.1}, 1e-15);
}

TEST(QuarticTest, DoubleRootIsReported) {
  double k[5];
  FromRoots(1.0, {-0.6, 0.3, 0.3, 0.9}, k);
  double roots[4];
  const int n = FindPolyRootsInInterval(k, -1, 1, {}, roots);
  ASSERT_GE(n, 3);
  EXPECT_NEAR(roots[0], -0.6, 1e-14);
  EXPECT_NEAR(roots[1], 0.3, 1e-7);  // a double root is only √eps-conditioned
  EXPECT_NEAR(roots[n - 1], 0.9, 1e-14);
}

// Two roots 1e-6 apart must not crowd out the other two (the local maximum between them is
// within the double-root tolerance of 0, yet it is no extra root).
TEST(QuarticTest, NearDoublePairKeepsTheOtherRoots) {
  double k[5];
  FromRoots(1.0, {-0.95, 0.3, 0.3 + 1e-6, 0.95}, k);
  ExpectRoots(k, {-0.95, 0.3, 0.3 + 1e-6, 0.95}, 1e-9);
}

TEST(QuarticTest, QuadrupleRootIsReported) {
  for (const double a : {0.0, 0.37}) {
    double k[5];
    FromRoots(2.0, {a, a, a, a}, k);
    for (const bool closed_form : {false, true}) {
      double roots[4];
      bool fallback = false;
      const int n = closed_form ? SolveQuarticInInterval(k, -1, 1, 2, {}, roots, &fallback)
                                : FindPolyRootsInInterval(k, -1, 1, {}, roots);
      ASSERT_GE(n, 1) << a;
      for (int i = 0; i < n; ++i) EXPECT_NEAR(roots[i], a, 2e-3) << a;  // 4th-root conditioning
    }
  }
}

TEST(QuarticTest, ClosedFormAgreesWithBracketedSearchOnRandomPolynomials) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int fallbacks = 0;
  for (int i = 0; i < 20000; ++i) {
    double k[5];
    for (double& c : k) c = u(rng);
    double a[4], b[4];
    bool fallback = false;
    const int na = FindPolyRootsInInterval(k, -1, 1, {}, a);
    const int nb = SolveQuarticInInterval(k, -1, 1, 2, {}, b, &fallback);
    fallbacks += fallback;
    ASSERT_EQ(na, nb) << i;
    for (int j = 0; j < na; ++j) {
      // Each reported root is a root: |p| small against |p'|·tol.
      EXPECT_NEAR(a[j], b[j], 1e-9) << i;
    }
  }
  // The closed form answers by itself almost always (the fallback is for degenerate input).
  EXPECT_LT(fallbacks, 200);
}

}  // namespace
}  // namespace microdex::geometry
