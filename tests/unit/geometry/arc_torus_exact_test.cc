#include "common/geometry/arc_torus_exact.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "tests/unit/geometry/brute_force_clearance.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry {
namespace {

using testing::CalcArcTorusClearanceBruteForce;
using testing::RandomArcTorus;

constexpr double kPi = std::numbers::pi;
// Agreement with the long-double reference, relative to the scene scale R.
constexpr double kRelTol = 1e-10;

RandomArcTorus OnCore(double R = 5e-3, double r = 0.5e-3, double sweep = kPi,
                      double omega = 2 * kPi) {
  RandomArcTorus c;
  c.torus.core_radius_m = R;
  c.torus.tube_radius_m = r;
  c.torus.segment_angle_rad = omega;
  c.arc.radius_m = R;
  c.arc.sweep_rad = sweep;
  return c;
}

// The needle pose given in the vessel frame.
void PlaceNeedle(RandomArcTorus* c, const Eigen::Vector3d& center_V, const Eigen::Matrix3d& R_VN) {
  Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
  X_VN.linear() = R_VN;
  X_VN.translation() = center_V;
  c->arc.X_WN = c->torus.X_WV * X_VN;
}

Eigen::Isometry3d SomePose(double translation_m) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(0.3, -0.8, 0.5) * translation_m;
  return X;
}

void ExpectMatchesBruteForce(const RandomArcTorus& c, int samples = 4096) {
  const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
  const auto reference = CalcArcTorusClearanceBruteForce(c.arc, c.torus, samples);
  ASSERT_EQ(exact.status, reference.status);
  if (exact.status != ClearanceStatus::kOk) return;
  const double tol = kRelTol * c.torus.core_radius_m;
  EXPECT_NEAR(exact.clearance_m, static_cast<double>(reference.clearance_m), tol)
      << "R " << c.torus.core_radius_m << " r " << c.torus.tube_radius_m << " rho "
      << c.arc.radius_m << " sweep " << c.arc.sweep_rad << " omega " << c.torus.segment_angle_rad
      << " s_exact " << exact.s_rad << " s_ref " << static_cast<double>(reference.s_rad);
}

TEST(ArcTorusExact, AgreesWithBruteForceOnWideRandomConfigurations) {
  std::mt19937_64 rng(1);
  int checked = 0;
  for (int i = 0; i < 50000; ++i) {
    const RandomArcTorus c = testing::MakeWideArcTorus(rng);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    const auto reference = CalcArcTorusClearanceBruteForce(c.arc, c.torus, 1024);
    ASSERT_EQ(exact.status, reference.status) << "case " << i;
    if (exact.status != ClearanceStatus::kOk) continue;
    ++checked;
    ASSERT_NEAR(exact.clearance_m, static_cast<double>(reference.clearance_m),
                kRelTol * c.torus.core_radius_m)
        << "case " << i;
  }
  EXPECT_GT(checked, 30000);
}

TEST(ArcTorusExact, AgreesWithBruteForceNearTheCoreCircle) {
  std::mt19937_64 rng(2);
  for (int i = 0; i < 50000; ++i) {
    const RandomArcTorus c = testing::MakeNearCoreArcTorus(rng);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    const auto reference = CalcArcTorusClearanceBruteForce(c.arc, c.torus, 1024);
    ASSERT_EQ(exact.status, reference.status) << "case " << i;
    if (exact.status != ClearanceStatus::kOk) continue;
    ASSERT_NEAR(exact.clearance_m, static_cast<double>(reference.clearance_m),
                kRelTol * c.torus.core_radius_m)
        << "case " << i;
  }
}

TEST(ArcTorusExact, NeedleOnTheCoreCircleHasClearanceR) {
  for (double sweep : {1e-6, 1.0, kPi, 2 * kPi}) {
    const RandomArcTorus c = OnCore(5e-3, 0.5e-3, sweep);
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    ASSERT_EQ(out.status, ClearanceStatus::kOk);
    EXPECT_NEAR(out.clearance_m, 0.5e-3, 1e-12 * 5e-3);
    EXPECT_FALSE(out.contact);
  }
}

TEST(ArcTorusExact, NeedleOnTheCoreCircleInGeneralPose) {
  RandomArcTorus c = OnCore(5e-3, 0.5e-3, 1.5 * kPi);
  c.torus.X_WV = SomePose(0.2);
  PlaceNeedle(&c, Eigen::Vector3d::Zero(),
              Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix());
  const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
  ASSERT_EQ(out.status, ClearanceStatus::kOk);
  EXPECT_NEAR(out.clearance_m, 0.5e-3, 1e-12 * 5e-3);
}

TEST(ArcTorusExact, CoaxialCircleHasConstantDistance) {
  // Needle of radius ρ in a horizontal plane at height h, centred on the z axis:
  // distance √((ρ − R)² + h²) everywhere.
  for (double rho : {0.2, 1.0, 1.7}) {
    RandomArcTorus c = OnCore(1, 0.9, 2 * kPi);
    c.arc.radius_m = rho;
    PlaceNeedle(&c, Eigen::Vector3d(0, 0, 0.3), Eigen::Matrix3d::Identity());
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    ASSERT_EQ(out.status, ClearanceStatus::kOk);
    EXPECT_NEAR(out.clearance_m, 0.9 - std::hypot(rho - 1, 0.3), 1e-12);
  }
}

TEST(ArcTorusExact, CoplanarNeedle) {
  // In the core circle's plane, centred at (a, 0, 0): |p_xy| spans [|a − ρ|, a + ρ] over the
  // full circle, so the largest distance is max(a + ρ − R, R − |a − ρ|).
  for (double a : {0.1, 0.5, 2.5}) {
    RandomArcTorus c = OnCore(1, 0.5, 2 * kPi);
    c.arc.radius_m = 0.8;
    PlaceNeedle(&c, Eigen::Vector3d(a, 0, 0), Eigen::Matrix3d::Identity());
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    ASSERT_EQ(out.status, ClearanceStatus::kOk);
    const double expected = 0.5 - std::max(a + 0.8 - 1, 1 - std::abs(a - 0.8));
    EXPECT_NEAR(out.clearance_m, expected, 1e-12) << "a " << a;
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, CoplanarSymmetricMaximumAtMidSweep) {
  // Arc from −S/2 to S/2 around the +x direction, centred at (a, 0, 0): the symmetric point
  // s = S/2 is a double root of P (A = B = 0 there).
  RandomArcTorus c = OnCore(1, 0.5, 1.0);
  c.arc.radius_m = 0.6;
  PlaceNeedle(&c, Eigen::Vector3d(0.2, 0, 0),
              Eigen::AngleAxisd(-0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix());
  const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
  ASSERT_EQ(out.status, ClearanceStatus::kOk);
  // k is largest at the middle (k = 0.8): distance 0.2 there; at the ends k < 0.8.
  ExpectMatchesBruteForce(c);
}

TEST(ArcTorusExact, ConcentricTiltedNeedle) {
  for (double tilt : {1e-9, 1e-3, 0.3, kPi / 2}) {
    RandomArcTorus c = OnCore(1, 0.5, 2 * kPi);
    PlaceNeedle(&c, Eigen::Vector3d::Zero(),
                Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix());
    ExpectMatchesBruteForce(c);
    // Symmetric: the farthest points are at s = ±π/2, at distance √((R cos β − R)² + (R sin β)²)
    // = 2R sin(β/2).
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    EXPECT_NEAR(out.clearance_m, 0.5 - 2 * std::sin(tilt / 2), 1e-12) << "tilt " << tilt;
  }
}

TEST(ArcTorusExact, NeedleThroughTheHole) {
  // Vertical arc in the xz-plane centred at the origin: it crosses the z axis at s = π/2,
  // where the distance √(R² + ρ²) is largest (a cusp of the distance, a double root of P).
  for (double rho : {0.3, 1.0, 3.0}) {
    RandomArcTorus c = OnCore(1, 0.4, kPi);
    c.arc.radius_m = rho;
    PlaceNeedle(&c, Eigen::Vector3d::Zero(),
                Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    ASSERT_EQ(out.status, ClearanceStatus::kOk);
    EXPECT_NEAR(out.clearance_m, 0.4 - std::hypot(1.0, rho), 1e-12) << "rho " << rho;
    EXPECT_TRUE(out.contact);
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, NeedlePassingNearTheAxis) {
  for (double offset : {1e-12, 1e-9, 1e-6, 1e-3}) {
    RandomArcTorus c = OnCore(1, 0.4, kPi);
    c.arc.radius_m = 0.7;
    PlaceNeedle(&c, Eigen::Vector3d(0.1, offset, -0.2),
                Eigen::AngleAxisd(kPi / 2 - 0.3, Eigen::Vector3d(1, 0.2, 0).normalized())
                    .toRotationMatrix());
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, VanishingSweep) {
  for (double sweep : {1e-15, 1e-9, 1e-5}) {
    RandomArcTorus c = OnCore(1, 0.5, sweep);
    PlaceNeedle(&c, Eigen::Vector3d(0.05, -0.1, 0.2), Eigen::Matrix3d::Identity());
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    ASSERT_EQ(out.status, ClearanceStatus::kOk);
    // The needle is (almost) the single point p(0) = (1.05, −0.1, 0.2).
    const double d0 = std::hypot(std::hypot(1.05, -0.1) - 1, 0.2);
    EXPECT_NEAR(out.clearance_m, 0.5 - d0, 1e-12 + sweep) << "sweep " << sweep;
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, FullAndAlmostFullSweep) {
  for (double sweep : {2 * kPi, 2 * kPi - 1e-12, 2 * kPi - 1e-6}) {
    RandomArcTorus c = OnCore(1, 0.5, sweep);
    c.arc.radius_m = 0.9;
    PlaceNeedle(&c, Eigen::Vector3d(0.05, -0.1, 0.2),
                Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix());
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, NeedleRadiusFarSmallerAndLargerThanCore) {
  for (double rho : {1e-6, 1e-3, 1e2, 1e3}) {
    RandomArcTorus c = OnCore(1, 0.5, 2.0);
    c.arc.radius_m = rho;
    PlaceNeedle(&c, Eigen::Vector3d(0.9, 0.3, 0.1),
                Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, 0).normalized()).toRotationMatrix());
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, TubeRadiusToZeroAndToCoreRadius) {
  for (double r : {1e-12, 1e-6, 1 - 1e-6, 1 - 1e-12}) {
    RandomArcTorus c = OnCore(1, r, kPi);
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    ASSERT_EQ(out.status, ClearanceStatus::kOk);
    EXPECT_NEAR(out.clearance_m, r, 1e-13);
    PlaceNeedle(&c, Eigen::Vector3d(0.01, 0.02, -0.03), Eigen::Matrix3d::Identity());
    ExpectMatchesBruteForce(c);
  }
}

TEST(ArcTorusExact, HugeTranslations) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) {
    const RandomArcTorus base = testing::MakeNearCoreArcTorus(rng);
    const double R = base.torus.core_radius_m;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(1e3, -7e2, 4e2) * R;
    ExpectMatchesBruteForce(testing::Transformed(base, X, 1.0));
  }
}

TEST(ArcTorusExact, TinyAndLargeScenes) {
  std::mt19937_64 rng(4);
  for (double R : {1e-6, 1e-3, 1.0, 1e3}) {
    for (int i = 0; i < 20; ++i) {
      const RandomArcTorus base = testing::MakeNearCoreArcTorus(rng);
      ExpectMatchesBruteForce(
          testing::Transformed(base, SomePose(R), R / base.torus.core_radius_m));
    }
  }
}

TEST(ArcTorusExact, ArcPartlyOutsideTheAzimuthRange) {
  // Coaxial needle (constant distance h) over half a turn, segment of a quarter turn: the
  // clearance is r − h and the deepest point lies in the segment.
  RandomArcTorus c = OnCore(1, 0.5, kPi, kPi / 2);
  PlaceNeedle(&c, Eigen::Vector3d(0, 0, 0.1),
              Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix());
  const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
  ASSERT_EQ(out.status, ClearanceStatus::kOk);
  EXPECT_NEAR(out.clearance_m, 0.4, 1e-12);
  EXPECT_GE(out.s_rad, 0.3 - 1e-12);
  EXPECT_LE(out.s_rad, 0.3 + kPi / 2 + 1e-12);
  // Coplanar needle off centre: the deepest point of the whole arc is out of the segment.
  RandomArcTorus d = OnCore(1, 0.5, 2 * kPi, 1.0);
  d.arc.radius_m = 0.8;
  PlaceNeedle(&d, Eigen::Vector3d(-0.3, 0.05, 0.02), Eigen::Matrix3d::Identity());
  ExpectMatchesBruteForce(d);
  const ArcTorusClearance clipped = CalcArcTorusClearanceExact(d.arc, d.torus);
  d.torus.segment_angle_rad = 2 * kPi;
  const ArcTorusClearance whole = CalcArcTorusClearanceExact(d.arc, d.torus);
  EXPECT_GT(clipped.clearance_m, whole.clearance_m + 1e-3);
}

TEST(ArcTorusExact, EmptyAzimuthRange) {
  RandomArcTorus c = OnCore(1, 0.5, 1.0, 1.0);
  PlaceNeedle(&c, Eigen::Vector3d::Zero(),
              Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ()).toRotationMatrix());
  const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
  EXPECT_EQ(out.status, ClearanceStatus::kEmptyRange);
  EXPECT_TRUE(std::isnan(out.clearance_m));
  EXPECT_FALSE(out.contact);
}

TEST(ArcTorusExact, InvalidInputIsReported) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const RandomArcTorus good = OnCore();
  auto expect_invalid = [](const RandomArcTorus& c, const char* what) {
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    EXPECT_EQ(out.status, ClearanceStatus::kInvalidInput) << what;
    EXPECT_TRUE(std::isnan(out.clearance_m)) << what;
    EXPECT_FALSE(out.contact) << what;
    EXPECT_FALSE(ValidateArcTorus(c.arc, c.torus).empty()) << what;
  };
  EXPECT_TRUE(ValidateArcTorus(good.arc, good.torus).empty());
  RandomArcTorus c = good;
  c.arc.radius_m = nan;
  expect_invalid(c, "nan needle radius");
  c = good;
  c.arc.radius_m = 0;
  expect_invalid(c, "zero needle radius");
  c = good;
  c.arc.radius_m = -1e-3;
  expect_invalid(c, "negative needle radius");
  c = good;
  c.arc.sweep_rad = 0;
  expect_invalid(c, "zero sweep");
  c = good;
  c.arc.sweep_rad = 2 * kPi + 1e-9;
  expect_invalid(c, "sweep > 2π");
  c = good;
  c.arc.sweep_rad = inf;
  expect_invalid(c, "infinite sweep");
  c = good;
  c.torus.tube_radius_m = c.torus.core_radius_m;
  expect_invalid(c, "r = R");
  c = good;
  c.torus.tube_radius_m = 2 * c.torus.core_radius_m;
  expect_invalid(c, "r > R");
  c = good;
  c.torus.tube_radius_m = 0;
  expect_invalid(c, "r = 0");
  c = good;
  c.torus.core_radius_m = -5e-3;
  expect_invalid(c, "negative R");
  c = good;
  c.torus.segment_angle_rad = 0;
  expect_invalid(c, "zero segment");
  c = good;
  c.torus.segment_angle_rad = 7;
  expect_invalid(c, "segment > 2π");
  c = good;
  c.arc.X_WN.translation().x() = nan;
  expect_invalid(c, "nan needle translation");
  c = good;
  c.torus.X_WV.translation().y() = inf;
  expect_invalid(c, "infinite vessel translation");
  c = good;
  c.arc.X_WN.linear()(0, 0) = 2;
  expect_invalid(c, "needle pose not a rotation");
  c = good;
  c.torus.X_WV.linear() = -Eigen::Matrix3d::Identity();
  expect_invalid(c, "vessel pose a reflection");
}

TEST(ArcTorusExact, InvariantUnderRigidMotions) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 2000; ++i) {
    const RandomArcTorus c =
        i % 2 ? testing::MakeWideArcTorus(rng) : testing::MakeNearCoreArcTorus(rng);
    const ArcTorusClearance a = CalcArcTorusClearanceExact(c.arc, c.torus);
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = testing::RandomRotation(rng).toRotationMatrix();
    X.translation() = Eigen::Vector3d::Random() * 10 * c.torus.core_radius_m;
    const RandomArcTorus moved = testing::Transformed(c, X, 1.0);
    const ArcTorusClearance b = CalcArcTorusClearanceExact(moved.arc, moved.torus);
    ASSERT_EQ(a.status, b.status) << i;
    if (a.status != ClearanceStatus::kOk) continue;
    const double tol = kRelTol * c.torus.core_radius_m;
    EXPECT_NEAR(a.clearance_m, b.clearance_m, tol) << i;
    EXPECT_LT((X * a.p_WN - b.p_WN).norm(), 1e-6 * c.torus.core_radius_m) << i;
  }
}

TEST(ArcTorusExact, ScalesWithTheScene) {
  std::mt19937_64 rng(6);
  for (int i = 0; i < 500; ++i) {
    const RandomArcTorus c =
        i % 2 ? testing::MakeWideArcTorus(rng) : testing::MakeNearCoreArcTorus(rng);
    const ArcTorusClearance a = CalcArcTorusClearanceExact(c.arc, c.torus);
    for (double scene_R : {1e-6, 1e-3, 1.0, 1e3}) {
      const double scale = scene_R / c.torus.core_radius_m;
      const RandomArcTorus s = testing::Transformed(c, Eigen::Isometry3d::Identity(), scale);
      const ArcTorusClearance b = CalcArcTorusClearanceExact(s.arc, s.torus);
      ASSERT_EQ(a.status, b.status);
      if (a.status != ClearanceStatus::kOk) continue;
      EXPECT_NEAR(b.clearance_m / scale, a.clearance_m, kRelTol * c.torus.core_radius_m)
          << i << " R " << scene_R;
    }
  }
}

TEST(ArcTorusExact, ClosestPointsAreConsistent) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 2000; ++i) {
    const RandomArcTorus c =
        i % 2 ? testing::MakeWideArcTorus(rng) : testing::MakeNearCoreArcTorus(rng);
    const ArcTorusClearance out = CalcArcTorusClearanceExact(c.arc, c.torus);
    if (out.status != ClearanceStatus::kOk) continue;
    const double R = c.torus.core_radius_m, r = c.torus.tube_radius_m;
    const double tol = 1e-9 * R * (1 + c.arc.radius_m / R);
    // p_WN is the needle point at s_rad, inside the azimuth range.
    const Eigen::Vector3d p_N(c.arc.radius_m * std::cos(out.s_rad),
                              c.arc.radius_m * std::sin(out.s_rad), 0);
    EXPECT_LT((c.arc.X_WN * p_N - out.p_WN).norm(), tol);
    EXPECT_GE(out.s_rad, 0);
    EXPECT_LE(out.s_rad, c.arc.sweep_rad);
    const Eigen::Vector3d p_V = c.torus.X_WV.inverse() * out.p_WN;
    const double omega = c.torus.segment_angle_rad;
    const bool on_end_plane = std::abs(p_V.y()) < tol ||
                              std::abs(p_V.x() * std::sin(omega) - p_V.y() * std::cos(omega)) < tol;
    EXPECT_TRUE(IsAzimuthInSegment(p_V.x(), p_V.y(), omega) || on_end_plane);
    // p_WW is on the wall, at distance |clearance| from p_WN.
    const Eigen::Vector3d w_V = c.torus.X_WV.inverse() * out.p_WW;
    EXPECT_NEAR(std::hypot(w_V.head<2>().norm() - R, w_V.z()), r, tol);
    EXPECT_NEAR((out.p_WW - out.p_WN).norm(), std::abs(out.clearance_m), tol);
  }
}

}  // namespace
}  // namespace microdex::geometry
