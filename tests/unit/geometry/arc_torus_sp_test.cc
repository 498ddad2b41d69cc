#include "common/geometry/arc_torus_sp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/stereographic.h"

namespace microdex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
// SP against the references, relative to the scene scale R.
constexpr double kRelTol = 1e-10;

struct Query {
  ArcDef arc;
  TorusSegmentDef torus;
};

Query MakeQuery(double R, double r, double rho, double sweep, double omega = 2 * kPi) {
  Query q;
  q.torus.core_radius_m = R;
  q.torus.tube_radius_m = r;
  q.torus.segment_angle_rad = omega;
  q.arc.radius_m = rho;
  q.arc.sweep_rad = sweep;
  return q;
}

// The needle pose given in the vessel frame.
void Place(Query* q, const Eigen::Vector3d& center_V, const Eigen::Matrix3d& R_VN) {
  Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
  X_VN.linear() = R_VN;
  X_VN.translation() = center_V;
  q->arc.X_WN = q->torus.X_WV * X_VN;
}

Eigen::Matrix3d Rot(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// Independent reference: the needle sampled densely in long double from the world poses,
// every sampled local maximum of the distance to the core circle refined by golden section,
// the azimuth boundaries located by bisection. NaN for an empty range.
long double DenseClearance(const Query& q, int samples = 20000) {
  using V = Eigen::Matrix<long double, 3, 1>;
  const Eigen::Matrix<long double, 4, 4> X_VN =
      (q.torus.X_WV.inverse().matrix() * q.arc.X_WN.matrix()).cast<long double>();
  const long double R = q.torus.core_radius_m, rho = q.arc.radius_m, S = q.arc.sweep_rad;
  const auto point = [&](long double s) {
    const V local(rho * std::cos(s), rho * std::sin(s), 0);
    return V(X_VN.block<3, 3>(0, 0) * local + X_VN.block<3, 1>(0, 3));
  };
  const auto inside = [&](long double s) {
    const V p = point(s);
    return IsAzimuthInSegment(static_cast<double>(p.x()), static_cast<double>(p.y()),
                              q.torus.segment_angle_rad);
  };
  const auto dist2 = [&](long double s) {
    const V p = point(s);
    const long double w = std::sqrt(p.x() * p.x() + p.y() * p.y());
    return (w - R) * (w - R) + p.z() * p.z();
  };
  long double best = -1;
  const auto consider = [&](long double s) {
    if (inside(s)) best = std::max(best, dist2(s));
  };
  std::vector<long double> f(samples + 1);
  std::vector<char> in(samples + 1);
  for (int i = 0; i <= samples; ++i) {
    const long double s = S * i / samples;
    in[i] = inside(s);
    f[i] = dist2(s);
    if (in[i]) best = std::max(best, f[i]);
    if (i > 0 && in[i] != in[i - 1]) {
      long double lo = S * (i - 1) / samples, hi = s;
      const bool lo_in = in[i - 1];
      for (int k = 0; k < 100; ++k) {
        const long double m = 0.5L * (lo + hi);
        (inside(m) == lo_in ? lo : hi) = m;
      }
      consider(lo_in ? lo : hi);
    }
  }
  for (int i = 0; i <= samples; ++i) {
    const bool local_max = (i == 0 || f[i] >= f[i - 1]) && (i == samples || f[i] >= f[i + 1]);
    // Flat stretches (a distance constant along the arc, up to rounding) need no refinement.
    const long double noise = 1e-13L * (f[i] + R * R);
    const bool flat =
        (i == 0 || f[i] - f[i - 1] <= noise) && (i == samples || f[i] - f[i + 1] <= noise);
    if (!in[i] || !local_max || flat) continue;
    long double lo = S * std::max(0, i - 1) / samples, hi = S * std::min(samples, i + 1) / samples;
    for (int k = 0; k < 200; ++k) {
      const long double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
      (dist2(m1) < dist2(m2) ? lo : hi) = dist2(m1) < dist2(m2) ? m1 : m2;
    }
    consider(0.5L * (lo + hi));
  }
  if (best < 0) return std::numeric_limits<long double>::quiet_NaN();
  return q.torus.tube_radius_m - std::sqrt(best);
}

// SP against the exact method and the dense reference; returns SP's result.
ArcTorusClearance ExpectAgrees(const Query& q, double rel_tol = kRelTol) {
  const ArcTorusClearance sp = CalcArcTorusClearanceSP(q.arc, q.torus);
  const ArcTorusClearance exact = CalcArcTorusClearanceExact(q.arc, q.torus);
  EXPECT_EQ(sp.status, exact.status);
  const long double dense = DenseClearance(q);
  if (sp.status != ClearanceStatus::kOk) {
    EXPECT_TRUE(std::isnan(sp.clearance_m));
    EXPECT_FALSE(sp.contact);
    return sp;
  }
  const double tol = rel_tol * q.torus.core_radius_m;
  EXPECT_NEAR(sp.clearance_m, exact.clearance_m, tol);
  EXPECT_NEAR(sp.clearance_m, static_cast<double>(dense), tol);
  if (std::abs(exact.clearance_m) > 1e-9 * q.torus.core_radius_m) {
    EXPECT_EQ(sp.contact, exact.contact);
  }
  EXPECT_EQ(sp.contact, sp.clearance_m <= 0);
  return sp;
}

// ---- Building blocks ---------------------------------------------------------------------

TEST(ArcTorusSpTest, LiftedCircleCarriesTheLiftedNeedleInOrder) {
  const Eigen::Vector3d o(0.4, -1.1, 0.3);
  const Eigen::Matrix3d R = Rot(0.9, Eigen::Vector3d(1, -2, 0.5));
  const Eigen::Vector3d e1 = R.col(0), e2 = R.col(1);
  const double rho = 0.8;
  const LiftedCircle lc = CalcLiftedCircle(o, e1, e2, rho);
  EXPECT_NEAR(lc.center.squaredNorm() + lc.radius * lc.radius, 1.0, 1e-14);
  EXPECT_NEAR(lc.bx.norm(), 1.0, 1e-14);
  EXPECT_NEAR(lc.by.norm(), 1.0, 1e-14);
  EXPECT_NEAR(lc.bx.dot(lc.by), 0.0, 1e-14);
  double prev_theta = -1;
  for (int i = 0; i < 64; ++i) {
    const double s = 2 * kPi * i / 64;
    const Eigen::Vector4d X = LiftToS3(o + rho * (std::cos(s) * e1 + std::sin(s) * e2));
    const Eigen::Vector4d d = X - lc.center;
    // On the circle: in its plane (4.13), at distance R̂ from c (4.9).
    EXPECT_NEAR(d.norm(), lc.radius, 1e-13);
    EXPECT_NEAR((d - d.dot(lc.bx) * lc.bx - d.dot(lc.by) * lc.by).norm(), 0.0, 1e-13);
    double theta = std::atan2(d.dot(lc.by), d.dot(lc.bx));
    if (theta < 0) theta += 2 * kPi;
    if (i == 0) {
      EXPECT_NEAR(std::min(theta, 2 * kPi - theta), 0.0, 1e-12);
      theta = 0;
    } else {
      EXPECT_GT(theta, prev_theta);  // θ grows with s (4.14)
    }
    prev_theta = theta;
  }
}

// The same on random needles from tiny (ρ = 1e-3) to large (ρ = 1e2), near and far from
// the origin (|o| up to 1e2): the lifted points of the needle lie on the circle (centre,
// radius and plane from the closed-form Gram system). The lift of a circle near the pole is
// small (R̂ down to ~5e-7 here) and its geometry carries an absolute rounding of a few ε, so
// the residuals are checked relative to R̂ within 1e-13 + 2e-15/R̂ (≈ 10 ε/R̂). The former
// Gram–Schmidt form reached 5.5e-8 relative on these needles, the closed form 1e-9.
TEST(ArcTorusSpTest, LiftedCircleOnRandomNeedles) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d o =
        std::pow(10.0, 2 * u(rng)) * Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Eigen::Matrix3d R = Rot(3 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const Eigen::Vector3d e1 = R.col(0), e2 = R.col(1);
    const double rho = std::pow(10.0, 2.5 * u(rng) - 0.5);
    const LiftedCircle lc = CalcLiftedCircle(o, e1, e2, rho);
    ASSERT_GT(lc.radius, 0) << i;
    const double tol = 1e-13 + 2e-15 / lc.radius;
    EXPECT_NEAR(lc.center.squaredNorm() + lc.radius * lc.radius, 1.0, 1e-13) << i;
    EXPECT_NEAR(lc.bx.norm(), 1.0, 1e-13) << i;
    EXPECT_NEAR(lc.by.norm(), 1.0, 1e-13) << i;
    EXPECT_NEAR(lc.bx.dot(lc.by), 0.0, tol) << i;
    for (int j = 0; j < 16; ++j) {
      const double s = 2 * kPi * j / 16;
      const Eigen::Vector4d X = LiftToS3(o + rho * (std::cos(s) * e1 + std::sin(s) * e2));
      const Eigen::Vector4d d = X - lc.center;
      const double err = std::max(std::abs(d.norm() - lc.radius),
                                  (d - d.dot(lc.bx) * lc.bx - d.dot(lc.by) * lc.by).norm()) /
                         lc.radius;
      worst = std::max(worst, err);
      EXPECT_LT(err, tol) << i << " s " << s << " radius " << lc.radius;
    }
    if (::testing::Test::HasFailure()) break;
  }
  std::printf("[ lifted circle ] worst relative residual %.3g\n", worst);
  EXPECT_LE(worst, 1e-9);  // README_sp.md: 6e-10
}

TEST(ArcTorusSpTest, ConicOnTheCircleIsTheLiftedTorus) {
  const double alpha = 0.37;
  const Eigen::Vector3d o(1.1, 0.2, -0.25);
  const Eigen::Matrix3d R = Rot(2.1, Eigen::Vector3d(0.3, 1, -0.7));
  const LiftedCircle lc = CalcLiftedCircle(o, R.col(0), R.col(1), 0.6);
  const CircleConic conic = CalcCircleConic(alpha, lc);
  for (int i = 0; i < 50; ++i) {
    const double t = 0.13 * i;
    const Eigen::Vector4d X =
        lc.center + lc.radius * (std::cos(t) * lc.bx + std::sin(t) * lc.by);  // (4.13)
    EXPECT_NEAR(conic.Eval(std::cos(t), std::sin(t)), EvalLiftedTorus(alpha, X), 1e-14);
  }
}

// The lifted torus along the needle (the quick certificate's form) is G on the lifted needle
// point times the positive factor (λ²|x|² + 1)²/λ⁴, so its sign is that of t − distance;
// checked against LiftToS3 and EvalLiftedTorus directly, on random needles and level tori.
TEST(ArcTorusSpTest, LevelTorusAlongNeedleIsTheLiftedTorus) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d o(1.5 * u(rng), 1.5 * u(rng), 0.5 * u(rng));
    const Eigen::Matrix3d R = Rot(3 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const double rho = 0.2 + 1.5 * unit(rng);
    const double t = 0.01 + 0.9 * unit(rng);
    double size = 0;
    const CircleConic g =
        CalcLevelTorusAlongNeedle(o, R.col(0), R.col(1), rho, rho * rho - 1, t * t, &size);
    ASSERT_GT(size, 0);
    const TorusLiftScale scale = CalcTorusLiftScale(1.0, t);
    const double lambda2 = scale.lambda * scale.lambda;
    for (int j = 0; j < 12; ++j) {
      const double s = 2 * kPi * unit(rng);
      const Eigen::Vector3d x = o + rho * (std::cos(s) * R.col(0) + std::sin(s) * R.col(1));
      const double factor =
          (lambda2 * x.squaredNorm() + 1) * (lambda2 * x.squaredNorm() + 1) / (lambda2 * lambda2);
      const double lifted =
          factor * EvalLiftedTorus(scale.alpha, LiftToS3(scale.lambda * x));  // (4.3), (4.4)
      EXPECT_NEAR(g.Eval(std::cos(s), std::sin(s)), lifted, 1e-13 * size) << i << " " << j;
      // Its sign: inside the level torus (distance < t) exactly where it is positive.
      const double d = std::hypot(std::hypot(x.x(), x.y()) - 1, x.z());
      if (std::abs(d - t) > 1e-9) {
        EXPECT_EQ(g.Eval(std::cos(s), std::sin(s)) > 0, d < t) << i << " " << j;
      }
    }
  }
}

CircleConic RandomConic(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  CircleConic k;
  k.a = u(rng);
  k.b = u(rng);
  k.c = u(rng);
  k.d = u(rng);
  k.e = u(rng);
  k.f = u(rng);
  return k;
}

// (4.21) as printed sets tan 2ψ = −b/d; the rotation that removes the u² − v² term of (4.20)
// has tan 2ψ = −b/g with g = c − a. Checked here, with (4.23) against φ'(θ) by differences.
TEST(ArcTorusSpTest, RotationRemovesTheUuVvTermAndGivesPhiPrime) {
  std::mt19937_64 rng(4);
  for (int i = 0; i < 500; ++i) {
    const CircleConic k = RandomConic(rng);
    const ExtremaCondition x = CalcExtremaCondition(k);
    const double g = k.c - k.a;
    const double c2 = x.cos_psi * x.cos_psi - x.sin_psi * x.sin_psi;
    const double s2 = 2 * x.sin_psi * x.cos_psi;
    EXPECT_NEAR(k.b * c2 + g * s2, 0.0, 1e-14);           // (4.20)–(4.21)
    EXPECT_NEAR(x.beta, 2 * (g * c2 - k.b * s2), 1e-14);  // (4.22)
    for (int j = 0; j < 8; ++j) {
      const double th = 0.77 * j + 0.1;
      const double h = 1e-6;
      const double dphi = (k.Eval(std::cos(th + h), std::sin(th + h)) -
                           k.Eval(std::cos(th - h), std::sin(th - h))) /
                          (2 * h);
      // (u, v) = rotation of (cos θ, sin θ) by −ψ (4.19).
      const double u = std::cos(th) * x.cos_psi + std::sin(th) * x.sin_psi;
      const double v = -std::cos(th) * x.sin_psi + std::sin(th) * x.cos_psi;
      EXPECT_NEAR(x.beta * u * v + x.gamma * u + x.delta * v, dphi, 1e-8);  // (4.23)
    }
  }
  // The printed angle does not remove the term for a generic conic.
  CircleConic k;
  k.a = 0.2;
  k.b = 0.5;
  k.c = -0.4;
  k.d = 0.9;
  const double psi_printed = -0.5 * std::atan(k.b / k.d);
  const double g = k.c - k.a;
  EXPECT_GT(std::abs(k.b * std::cos(2 * psi_printed) + g * std::sin(2 * psi_printed)), 0.1);
}

// Every local minimum and maximum of φ on a dense θ grid is among the extrema from (4.26).
void ExpectExtremaFound(const CircleConic& k, const SpOptions& opt) {
  double ct[8], st[8];
  bool constant = false;
  const int n = FindConicExtremaOnCircle(k, opt, ct, st, &constant);
  ASSERT_FALSE(constant);
  const int m = 20000;
  std::vector<double> phi(m);
  for (int i = 0; i < m; ++i) phi[i] = k.Eval(std::cos(2 * kPi * i / m), std::sin(2 * kPi * i / m));
  for (int i = 0; i < m; ++i) {
    const double a = phi[(i + m - 1) % m], b = phi[i], c = phi[(i + 1) % m];
    if (!((b < a && b < c) || (b > a && b > c))) continue;
    const double th = 2 * kPi * i / m;
    double nearest = 10;
    for (int j = 0; j < n; ++j) {
      nearest = std::min(nearest, std::hypot(ct[j] - std::cos(th), st[j] - std::sin(th)));
    }
    EXPECT_LT(nearest, 5 * 2 * kPi / m) << "extremum at θ = " << th << " missed";
  }
}

TEST(ArcTorusSpTest, ExtremaOfRandomConicsMatchDenseSampling) {
  std::mt19937_64 rng(5);
  for (const auto method : {SpQuarticMethod::kClosedForm, SpQuarticMethod::kNewton}) {
    SpOptions opt;
    opt.quartic_method = method;
    for (int i = 0; i < 200; ++i) ExpectExtremaFound(RandomConic(rng), opt);
  }
}

// β = δ = 0: (4.23) reduces to γu = 0, the extrema at u = 0 (θ = ψ ± π/2).
TEST(ArcTorusSpTest, BetaAndDeltaZero) {
  CircleConic k;  // φ = 0.3 + 0.8 sin θ: isotropic quadratic part (β = 0), D = 0 (δ = 0)
  k.a = 0.3;
  k.c = 0.3;
  k.e = 0.8;
  const ExtremaCondition x = CalcExtremaCondition(k);
  EXPECT_EQ(x.beta, 0.0);
  EXPECT_NEAR(x.delta, 0.0, 1e-16);
  for (const auto method : {SpQuarticMethod::kClosedForm, SpQuarticMethod::kNewton}) {
    SpOptions opt;
    opt.quartic_method = method;
    ExpectExtremaFound(k, opt);
  }
}

// δ = 0 with β ≠ 0: u = 0 is a double root of (4.26) that stands for two extrema (v = ±1).
TEST(ArcTorusSpTest, QuarticDoubleRoot) {
  CircleConic k;  // φ = 0.2 cos² + 0.9 sin² + 0.3 sin θ: B = 0, g > 0 → ψ = 0, δ = −D = 0
  k.a = 0.2;
  k.c = 0.9;
  k.e = 0.3;
  for (const auto method : {SpQuarticMethod::kClosedForm, SpQuarticMethod::kNewton}) {
    SpOptions opt;
    opt.quartic_method = method;
    ExpectExtremaFound(k, opt);
  }
}

// γ = ±β, δ = 0: (4.26) is β²u⁴, a quadruple root at u = 0. φ = sin² θ + 2 sin θ has its
// maximum at θ = π/2 and a flat minimum (φ' ∝ ε³) at θ = −π/2, both at u = 0.
TEST(ArcTorusSpTest, QuarticQuadrupleRoot) {
  CircleConic k;
  k.c = 1;
  k.e = 2;
  const ExtremaCondition x = CalcExtremaCondition(k);
  EXPECT_NEAR(std::abs(x.gamma), x.beta, 1e-15);
  EXPECT_NEAR(x.delta, 0.0, 1e-15);
  for (const auto method : {SpQuarticMethod::kClosedForm, SpQuarticMethod::kNewton}) {
    SpOptions opt;
    opt.quartic_method = method;
    double ct[8], st[8];
    bool constant = false;
    const int n = FindConicExtremaOnCircle(k, opt, ct, st, &constant);
    bool found_min = false, found_max = false;
    for (int j = 0; j < n; ++j) {
      found_min = found_min || (std::abs(ct[j]) < 1e-3 && st[j] < 0);
      found_max = found_max || (std::abs(ct[j]) < 1e-3 && st[j] > 0);
    }
    EXPECT_TRUE(found_min);
    EXPECT_TRUE(found_max);
  }
}

// ---- Degenerate and extreme needle / vessel configurations --------------------------------

// The ideal training path: the needle on the core circle. φ is constant along it (the conic
// is degenerate along the arc); the clearance is r everywhere.
TEST(ArcTorusSpTest, NeedleOnCoreCircle) {
  for (const double start : {0.0, 1.0, 4.0}) {
    Query q = MakeQuery(5e-3, 0.6e-3, 5e-3, 2.0);
    Place(&q, Eigen::Vector3d::Zero(), Rot(start, Eigen::Vector3d::UnitZ()));
    SpDiagnostics diag;
    const ArcTorusClearance sp = CalcArcTorusClearanceSP(q.arc, q.torus, {}, &diag);
    ASSERT_EQ(sp.status, ClearanceStatus::kOk);
    EXPECT_NEAR(sp.clearance_m, 0.6e-3, 1e-12 * 5e-3);
    EXPECT_FALSE(sp.contact);
    EXPECT_TRUE(diag.phi_constant);
    ExpectAgrees(q);
  }
}

// Close to the ideal path: tiny offsets and tilts (the conic is nearly degenerate).
TEST(ArcTorusSpTest, NeedleNearCoreCircle) {
  for (const double eps : {1e-12, 1e-9, 1e-6, 1e-3}) {
    Query q = MakeQuery(5e-3, 0.6e-3, 5e-3 * (1 + eps), 2.5);
    Place(&q, Eigen::Vector3d(eps, -2 * eps, 3 * eps) * 5e-3, Rot(eps, Eigen::Vector3d(1, 1, 0)));
    ExpectAgrees(q);
  }
}

TEST(ArcTorusSpTest, NeedleCoplanarWithCoreCircle) {
  for (const double rho : {0.5, 0.95, 1.0, 1.3}) {
    Query q = MakeQuery(5e-3, 0.5e-3, rho * 5e-3, 4.0);
    Place(&q, Eigen::Vector3d(0.3e-3, -0.2e-3, 0), Rot(0.4, Eigen::Vector3d::UnitZ()));
    ExpectAgrees(q);
  }
}

TEST(ArcTorusSpTest, NeedleConcentricWithCoreCircle) {
  const double R = 5e-3, r = 0.5e-3;
  // In the core plane (a parallel circle: distance |ρ − R| everywhere) and lifted off it.
  for (const double h : {0.0, 0.2e-3, 0.7e-3}) {
    Query q = MakeQuery(R, r, R + 0.3e-3, 3.0);
    Place(&q, Eigen::Vector3d(0, 0, h), Eigen::Matrix3d::Identity());
    const ArcTorusClearance sp = ExpectAgrees(q);
    EXPECT_NEAR(sp.clearance_m, r - std::hypot(0.3e-3, h), 1e-12 * R);
  }
}

// A Villarceau circle of the tube lies on the wall: clearance 0 along the whole arc (φ ≡ 0).
TEST(ArcTorusSpTest, NeedleOnVillarceauCircle) {
  const double R = 5e-3, r = 1.5e-3;
  Query q = MakeQuery(R, r, R, 2 * kPi);
  // The bitangent plane through the centre, tilted by asin(r/R) about the x axis; the circle
  // of radius R centred at (r, 0, 0) in it.
  Place(&q, Eigen::Vector3d(r, 0, 0), Rot(std::asin(r / R), Eigen::Vector3d::UnitX()));
  const ArcTorusClearance sp = CalcArcTorusClearanceSP(q.arc, q.torus);
  ASSERT_EQ(sp.status, ClearanceStatus::kOk);
  EXPECT_NEAR(sp.clearance_m, 0.0, 1e-12 * R);
  EXPECT_NEAR(CalcArcTorusClearanceExact(q.arc, q.torus).clearance_m, 0.0, 1e-12 * R);
}

TEST(ArcTorusSpTest, SweepToZero) {
  for (const double sweep : {1e-12, 1e-8, 1e-4}) {
    Query q = MakeQuery(5e-3, 0.5e-3, 4.8e-3, sweep);
    Place(&q, Eigen::Vector3d(0.1e-3, 0.05e-3, 0.2e-3), Rot(0.3, Eigen::Vector3d(0.2, 0.1, 1)));
    ExpectAgrees(q);
  }
}

TEST(ArcTorusSpTest, SweepToFullCircle) {
  for (const double sweep : {2 * kPi - 1e-9, 2 * kPi}) {
    Query q = MakeQuery(5e-3, 0.5e-3, 5.1e-3, sweep);
    Place(&q, Eigen::Vector3d(0.1e-3, 0.05e-3, 0.2e-3), Rot(0.05, Eigen::Vector3d(1, 0.1, 0)));
    ExpectAgrees(q);
  }
}

TEST(ArcTorusSpTest, NeedleMuchSmallerThanR) {
  const double R = 5e-3, r = 0.5e-3;
  for (const double rho : {1e-4 * R, 1e-7 * R}) {
    Query q = MakeQuery(R, r, rho, 5.0);
    // Just inside the wall, on the outer equator.
    Place(&q, Eigen::Vector3d(R + r - 2 * rho, 0.1 * rho, 0), Rot(1.0, Eigen::Vector3d(1, 2, 3)));
    ExpectAgrees(q);
  }
}

TEST(ArcTorusSpTest, NeedleMuchLargerThanR) {
  const double R = 5e-3, r = 0.5e-3;
  for (const double rho : {1e2 * R, 1e4 * R}) {
    Query q = MakeQuery(R, r, rho, 2 * kPi);
    // The needle circle passes through the core circle point (R, 0, 0), crossing the tube.
    Place(&q, Eigen::Vector3d(R, 0, 0) - rho * Eigen::Vector3d(0.6, 0, 0.8),
          Rot(-std::atan2(0.8, 0.6), Eigen::Vector3d::UnitY()));
    const ArcTorusClearance sp = ExpectAgrees(q, 1e-9);
    EXPECT_TRUE(sp.contact);
  }
}

TEST(ArcTorusSpTest, TubeRadiusToZero) {
  const double R = 5e-3;
  for (const double r : {1e-5 * R, 1e-8 * R}) {
    Query q = MakeQuery(R, r, R, 1.5);
    Place(&q, Eigen::Vector3d(0, 0, 0.3 * r), Eigen::Matrix3d::Identity());
    const ArcTorusClearance sp = ExpectAgrees(q);
    EXPECT_NEAR(sp.clearance_m, 0.7 * r, 1e-12 * R);
  }
}

TEST(ArcTorusSpTest, TubeRadiusToR) {
  const double R = 5e-3;
  for (const double r : {0.999 * R, (1 - 1e-6) * R}) {
    Query q = MakeQuery(R, r, 0.7 * R, 3.0);
    Place(&q, Eigen::Vector3d(0.2e-3, 0.1e-3, 0.3e-3), Rot(0.8, Eigen::Vector3d(1, 0, 1)));
    ExpectAgrees(q);
  }
}

// A needle through the hole of the torus: its points near the axis are farther than R from
// the core circle (spindle level sets; the exact method answers there).
TEST(ArcTorusSpTest, NeedleThroughTorusHole) {
  const double R = 5e-3, r = 0.8e-3;
  Query q = MakeQuery(R, r, 0.5 * R, 2 * kPi);
  Place(&q, Eigen::Vector3d(0.1e-3, 0, 0.2e-3), Rot(kPi / 2, Eigen::Vector3d::UnitX()));
  SpDiagnostics diag;
  const ArcTorusClearance sp = CalcArcTorusClearanceSP(q.arc, q.torus, {}, &diag);
  EXPECT_TRUE(sp.contact);
  EXPECT_TRUE(diag.deep_fallback());
  ExpectAgrees(q);
  // And a small needle crossing the hole through the wall near the inner equator.
  Query q2 = MakeQuery(R, r, 1.2 * r, kPi);
  Place(&q2, Eigen::Vector3d(R - r, 0, 0), Rot(kPi / 2, Eigen::Vector3d::UnitX()));
  ExpectAgrees(q2);
}

// The deepest point on the z axis, where the distance has a ridge (every core point is as far,
// √(R² + z²)): the level set through it is the spindle torus whose tip is that very point, where
// the quick test's error bound vanishes, so the certificate must not claim it. The needle lies
// in the yz-plane, curving down from (0, 0, z₀) both ways, so that its top is the deepest point
// (d² = R² + ρ² − (z₀ − ρ)² + 2z(z₀ − ρ) − 2R|y| on it); then moved off the axis.
TEST(ArcTorusSpTest, DeepestPointAtTheSpindleTip) {
  const double R = 5e-3, r = 0.5e-3, z0 = 1.5 * R, rho = 0.8 * R, sweep = 0.6 * kPi;
  Query q = MakeQuery(R, r, rho, sweep);
  const double beta = kPi / 2 - sweep / 2;  // the needle's mid-sweep point on the axis
  Eigen::Matrix3d R_VN;
  R_VN.col(0) = Eigen::Vector3d(0, std::cos(beta), std::sin(beta));
  R_VN.col(1) = Eigen::Vector3d(0, -std::sin(beta), std::cos(beta));
  R_VN.col(2) = Eigen::Vector3d::UnitX();
  Place(&q, Eigen::Vector3d(0, 0, z0 - rho), R_VN);
  const ArcTorusClearance sp = ExpectAgrees(q);
  EXPECT_NEAR(sp.clearance_m, r - std::sqrt(R * R + z0 * z0), 1e-12 * R);
  EXPECT_NEAR(sp.s_rad, sweep / 2, 1e-6);
  for (const double off : {1e-12, 1e-9, 1e-6, 1e-3, 0.1}) {
    Place(&q, Eigen::Vector3d(off * R, 0, z0 - rho), R_VN);
    ExpectAgrees(q);
  }
}

// The projection pole is the image of ∞ and of points far from the torus in the scaled
// frame; its antipode is the torus centre. Needles reaching far out and through the centre.
TEST(ArcTorusSpTest, PointsNearProjectionPole) {
  const double R = 5e-3, r = 0.5e-3;
  {
    Query q = MakeQuery(R, r, 300 * R, 0.02);
    // A long flat arc whose middle grazes the tube's outer equator at (R + r/2, 0, 0).
    Place(&q, Eigen::Vector3d(R + 0.5 * r + 300 * R, 0, 0),
          Rot(kPi - 0.01, Eigen::Vector3d::UnitZ()));
    ExpectAgrees(q, 1e-9);
  }
  {
    Query q = MakeQuery(R, r, 0.5 * R, kPi);
    Place(&q, Eigen::Vector3d(0.5 * R, 0, 0), Eigen::Matrix3d::Identity());  // through the centre
    ExpectAgrees(q);
  }
}

TEST(ArcTorusSpTest, HugeTranslationAndTinyScale) {
  Query base = MakeQuery(5e-3, 0.5e-3, 5.2e-3, 2.0);
  Place(&base, Eigen::Vector3d(0.1e-3, -0.2e-3, 0.15e-3), Rot(0.05, Eigen::Vector3d(1, 2, 0)));
  const double c0 = CalcArcTorusClearanceSP(base.arc, base.torus).clearance_m;
  // Both frames moved by 1e3·R.
  Query far = base;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Rot(1.3, Eigen::Vector3d(3, -1, 2));
  X.translation() = Eigen::Vector3d(1, -2, 0.5).normalized() * 1e3 * 5e-3;
  far.arc.X_WN = X * base.arc.X_WN;
  far.torus.X_WV = X * base.torus.X_WV;
  EXPECT_NEAR(CalcArcTorusClearanceSP(far.arc, far.torus).clearance_m, c0, 1e-10 * 5e-3);
  ExpectAgrees(far);
  // Every length scaled to micrometres (R = 5 µm … 5e-9 m).
  for (const double k : {1e-3, 1e-6}) {
    Query tiny = base;
    tiny.arc.radius_m *= k;
    tiny.torus.core_radius_m *= k;
    tiny.torus.tube_radius_m *= k;
    tiny.arc.X_WN.translation() *= k;
    tiny.torus.X_WV.translation() *= k;
    const ArcTorusClearance sp = ExpectAgrees(tiny);
    EXPECT_NEAR(sp.clearance_m, k * c0, 1e-12 * k * 5e-3);
  }
}

TEST(ArcTorusSpTest, SegmentClipsTheArc) {
  const double R = 5e-3, r = 0.5e-3;
  // The needle leaves the tube at azimuth ≈ 1.2; a segment ending before that sees no contact.
  Query q = MakeQuery(R, r, R, 2.0, 1.0);
  Place(&q, Eigen::Vector3d(0, 0, 0),
        Rot(0.3, Eigen::Vector3d::UnitZ()) * Rot(0.15, Eigen::Vector3d::UnitX()));
  for (const double omega : {0.5, 1.0, 2.0, 4.0, 2 * kPi}) {
    q.torus.segment_angle_rad = omega;
    ExpectAgrees(q);
  }
  // Entirely outside the segment: empty range.
  Query e = MakeQuery(R, r, R, 1.0, 1.0);
  Place(&e, Eigen::Vector3d::Zero(), Rot(3.0, Eigen::Vector3d::UnitZ()));
  const ArcTorusClearance sp = CalcArcTorusClearanceSP(e.arc, e.torus);
  EXPECT_EQ(sp.status, ClearanceStatus::kEmptyRange);
  EXPECT_TRUE(std::isnan(sp.clearance_m));
  EXPECT_FALSE(sp.contact);
}

TEST(ArcTorusSpTest, InvalidInputIsReportedNotCrashed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Query good = MakeQuery(5e-3, 0.5e-3, 5e-3, 1.0);
  std::vector<Query> bad;
  for (const double v : {nan, inf, 0.0, -1e-3}) {
    Query q = good;
    q.arc.radius_m = v;
    bad.push_back(q);
    q = good;
    q.torus.core_radius_m = v;
    bad.push_back(q);
    q = good;
    q.torus.tube_radius_m = v;
    bad.push_back(q);
  }
  for (const double v : {nan, 0.0, -0.1, 2 * kPi + 1e-9, 7.0}) {
    Query q = good;
    q.arc.sweep_rad = v;
    bad.push_back(q);
    q = good;
    q.torus.segment_angle_rad = v;
    bad.push_back(q);
  }
  {
    Query q = good;
    q.torus.tube_radius_m = q.torus.core_radius_m;  // r = R
    bad.push_back(q);
    q.torus.tube_radius_m = 2 * q.torus.core_radius_m;  // r > R
    bad.push_back(q);
    q = good;
    q.arc.X_WN.translation().x() = nan;
    bad.push_back(q);
    q = good;
    q.torus.X_WV.linear() *= 1.01;  // not a rotation
    bad.push_back(q);
  }
  for (const Query& q : bad) {
    const ArcTorusClearance sp = CalcArcTorusClearanceSP(q.arc, q.torus);
    EXPECT_EQ(sp.status, ClearanceStatus::kInvalidInput);
    EXPECT_TRUE(std::isnan(sp.clearance_m));
    EXPECT_FALSE(sp.contact);
  }
}

// §4.2.4: an arc crossing the wall twice has two sign changes of φ; one inside has none.
TEST(ArcTorusSpTest, SignChangesOfPhiCountWallCrossings) {
  const double R = 5e-3, r = 0.5e-3;
  Query in = MakeQuery(R, r, R, 2.0);
  Place(&in, Eigen::Vector3d(0, 0, 0.2 * r), Rot(0.02, Eigen::Vector3d::UnitX()));
  SpDiagnostics d_in;
  CalcArcTorusClearanceSP(in.arc, in.torus, {}, &d_in);
  EXPECT_EQ(d_in.num_sign_changes, 0);
  EXPECT_GT(d_in.min_phi, 0);
  // A small needle whose middle pokes out through the top of the tube.
  Query out = MakeQuery(R, r, 2 * r, kPi);
  Place(&out, Eigen::Vector3d(R, 0, -0.6 * r),
        Rot(kPi / 2, Eigen::Vector3d::UnitY()) * Rot(0, Eigen::Vector3d::UnitZ()));
  SpDiagnostics d_out;
  const ArcTorusClearance sp = CalcArcTorusClearanceSP(out.arc, out.torus, {}, &d_out);
  const ArcTorusClearance exact = CalcArcTorusClearanceExact(out.arc, out.torus);
  ASSERT_TRUE(exact.contact);
  EXPECT_TRUE(sp.contact);
  EXPECT_LT(d_out.min_phi, 0);
  EXPECT_EQ(d_out.num_sign_changes % 2, 0);
  EXPECT_GE(d_out.num_sign_changes, 1);
}

TEST(ArcTorusSpTest, ClosestPointsAreConsistent) {
  Query q = MakeQuery(5e-3, 0.5e-3, 5.1e-3, 2.0);
  Place(&q, Eigen::Vector3d(0.1e-3, 0.2e-3, 0.1e-3), Rot(0.1, Eigen::Vector3d(1, 1, 0)));
  q.torus.X_WV.translation() = Eigen::Vector3d(0.01, -0.02, 0.03);
  q.torus.X_WV.linear() = Rot(0.4, Eigen::Vector3d(0, 1, 1));
  q.arc.X_WN = q.torus.X_WV * q.arc.X_WN;
  const ArcTorusClearance sp = CalcArcTorusClearanceSP(q.arc, q.torus);
  ASSERT_EQ(sp.status, ClearanceStatus::kOk);
  const Eigen::Vector3d p_N(q.arc.radius_m * std::cos(sp.s_rad),
                            q.arc.radius_m * std::sin(sp.s_rad), 0);
  EXPECT_LE((q.arc.X_WN * p_N - sp.p_WD).norm(), 1e-15);
  // The wall point is at distance r from the core circle and |clearance| from the needle point.
  const Eigen::Vector3d w_V = q.torus.X_WV.inverse() * sp.p_WB;
  EXPECT_NEAR(std::hypot(std::hypot(w_V.x(), w_V.y()) - 5e-3, w_V.z()), 0.5e-3, 1e-15);
  EXPECT_NEAR((sp.p_WB - sp.p_WD).norm(), std::abs(sp.clearance_m), 1e-15);
}

}  // namespace
}  // namespace microdex::geometry
