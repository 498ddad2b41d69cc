#include "common/geometry/arc_torus_exact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

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

// Needles of radius 1e3·R through the wall of a segment, from the SP agreement test's
// adversarial set, where the exact method was once off by up to 0.12·R: only an O(R/ρ)
// parameter interval is near the tube, and P's global coefficients, of size (|c| + ρ)⁶, cancel
// down to P there. Every input to 17 digits: R, r, ρ, S, Ω, then the 3×4 poses X_WN, X_WV.
struct RecordedCase {
  double R, r, rho, sweep, omega;
  double X_WN[12], X_WV[12];
};
constexpr RecordedCase kHugeNeedleCases[] = {
    {0.0094951247919301159,
     0.0028436264063042504,
     9.4951247919301167,
     0.45728480428163931,
     2.42077628248706,
     {-0.75997575017539676, 0.44938077090524831, 0.46956765421603364, 7.1862765239934658,
      0.60379204685323629, 0.75554056183425722, 0.25415275638866358, -5.7772295677303998,
      -0.24056604769194473, 0.47667114677079098, -0.84552504074929469, 2.2431045214898062},
     {-0.70832739836107139, -0.48799805348069997, -0.51002960358207117, -0.013778270167637864,
      0.52973610285032746, -0.84502971688614448, 0.072831579114216768, -0.042772826482455464,
      -0.46653184035817336, -0.2185924915873621, 0.85706788794916644, -0.034107838676749505}},
    {0.0058197741095995098,
     0.0018694921599611866,
     5.8197741095995097,
     2.819916503402069,
     3.7824091418333095,
     {0.0097726417887353811, 0.84078820459114612, -0.54127598366532614, -0.07226693041820853,
      -0.85233967169745273, -0.27605467326869781, -0.44419691738821404, 4.9632272821163976,
      -0.52289729347468272, 0.46569197157231568, 0.71393935883234638, 3.0189639995963797},
     {0.5942407885125478, -0.0047985127204058231, -0.80427287629489141, -0.01156771971437099,
      0.80284440123055445, 0.063408853094016449, 0.59280703838774929, 0.0085216518429899416,
      0.048153428546035326, -0.99797609772227203, 0.041532585933075961, -0.027849676435887628}},
    {0.0095390809770564133,
     0.0036088195866735696,
     9.5390809770564129,
     5.2119254911197572,
     1.6059559896718758,
     {-0.147267254342138, -0.097573518081122246, -0.98427220034287299, 1.4090973295269933,
      -0.90913960033316743, -0.37860634118288383, 0.17355813297612357, 8.6374154766160736,
      -0.38958637412591335, 0.92040026455090862, -0.032951632888846435, 3.7104521093577398},
     {-0.010262808709059046, -0.95261102042544432, -0.30401795756401445, 0.01571870596988453,
      0.80858418333226778, -0.1867757932583074, 0.55794840399235801, -0.036322825712257457,
      -0.58829099366069748, -0.24009799419554437, 0.77218304822171902, 0.0010416068236957844}},
    {0.0026711952638457754,
     0.00080445870880379504,
     2.6711952638457754,
     2.9807664041804691,
     0.32523392188596867,
     {-0.33000545226338046, 0.49015410572260631, 0.80674987085199668, 0.90509469753011151,
      -0.94063898085790332, -0.098917222660310555, -0.32467474609488001, 2.5263412835844905,
      -0.079339203216606341, -0.86600481274900676, 0.4937012812708832, 0.21803328326065424},
     {-0.89367921668253203, -0.42559834334878183, -0.14213904392695279, 0.025445931881813912,
      0.42610025188743822, -0.70567057157113888, -0.56609859544069152, 0.012622539860331496,
      0.14062728402112248, -0.56647603175883299, 0.81199068494140259, 0.0045476191453525661}},
    {0.00423014105593255,
     0.00026478334296422309,
     4.2301410559325499,
     3.3187252364422664,
     2.4619799184160853,
     {0.71416401813299157, -0.16213202635322244, 0.68094270040491489, -3.0314222700106681,
      -0.67981913103810898, 0.07113177661339723, 0.72992206394272741, 2.8576024371526154,
      -0.16678040735868649, -0.98420194898527757, -0.059420697865733174, 0.7480707062124099},
     {0.046416710903619873, -0.31205860785663375, 0.94892829771878406, -0.010741564827880102,
      0.59142913639113948, -0.75697038599865873, -0.27786221648268783, -0.01359032497822879,
      0.80501991626078451, 0.57412129379045052, 0.14942447737856912, 0.039833858862082544}},
    {0.0079921385796109402,
     0.00085844185376798604,
     7.9921385796109403,
     0.4958106473148558,
     1.8618666722600901,
     {-0.22433725420952427, 0.82177173830489547, 0.52379767706346414, 1.8384570462698873,
      0.9740579198980388, 0.20548635933029258, 0.09479728273050686, -7.7696191513255526,
      -0.029731549869406293, 0.53147583788214814, -0.84655151567393161, 0.27358084565477314},
     {-0.37930304702026874, 0.41936320065890464, 0.82478100393635323, 0.04238446386206042,
      0.33148804086428407, 0.89381288159553907, -0.30201690591395314, 0.0062253233618067899,
      -0.8638546621307881, 0.15884910647214279, -0.47803983525215066, 0.035436421118239102}},
    {0.0034678916044531861,
     0.0015379867248192472,
     3.467891604453186,
     1.0062752965893971,
     2.9964471997269024,
     {-0.83226326528839345, 0.11158746407621312, 0.5430341564879152, 2.9011970057579868,
      0.45781532665718927, 0.69074111155237494, 0.55971585960124537, -1.5653740499244222,
      -0.31263874348722814, 0.71444030868395847, -0.62596490428641238, 1.0554026704463706},
     {-0.45791874313781422, 0.44606014596204735, -0.76898684700546216, 0.015608122179300033,
      -0.3071396416131903, -0.89112402330448237, -0.33401080168065489, 0.026209616041300534,
      -0.83425155992230904, 0.083236538094455664, 0.54506514610021106, -0.026237828158319501}},
};

TEST(ArcTorusExact, HugeNeedleThroughTheWallOfASegment) {
  for (const RecordedCase& rc : kHugeNeedleCases) {
    RandomArcTorus c;
    c.torus.core_radius_m = rc.R;
    c.torus.tube_radius_m = rc.r;
    c.torus.segment_angle_rad = rc.omega;
    c.arc.radius_m = rc.rho;
    c.arc.sweep_rad = rc.sweep;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 4; ++j) {
        c.arc.X_WN.matrix()(i, j) = rc.X_WN[4 * i + j];
        c.torus.X_WV.matrix()(i, j) = rc.X_WV[4 * i + j];
      }
    }
    ExpectMatchesBruteForce(c, 8192);
  }
}

// ρ/R from 1e-3 to 1e4, through a random point 0.5–1.5 r from the core circle inside the
// segment, random orientation, whole tori and segments. The needle's arc length is capped at
// 30·R so that the long-double oracle samples it every 0.002·R.
TEST(ArcTorusExact, NeedleRadiusSweepAgainstBruteForce) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0, 1);
  for (int decade = -3; decade < 4; ++decade) {
    for (int i = 0; i < 40; ++i) {
      RandomArcTorus c;
      const double R = 1, r = 0.03 + 0.5 * u(rng);
      c.torus.core_radius_m = R;
      c.torus.tube_radius_m = r;
      c.torus.segment_angle_rad = u(rng) < 0.3 ? 2 * kPi : 0.1 + 6 * u(rng);
      const double rho = std::pow(10.0, decade + u(rng));
      c.arc.radius_m = rho;
      const double length = std::min(2 * kPi * rho, 0.05 + 30 * u(rng));
      c.arc.sweep_rad = std::min(2 * kPi, length / rho);
      const double phi = c.torus.segment_angle_rad * u(rng), psi = 2 * kPi * u(rng);
      const double rr = r * (0.5 + u(rng));
      const Eigen::Vector3d q((R + rr * std::cos(psi)) * std::cos(phi),
                              (R + rr * std::cos(psi)) * std::sin(phi), rr * std::sin(psi));
      const Eigen::Matrix3d R_VN = testing::RandomRotation(rng).toRotationMatrix();
      const double s0 = c.arc.sweep_rad * u(rng);
      PlaceNeedle(&c, q - R_VN * Eigen::Vector3d(rho * std::cos(s0), rho * std::sin(s0), 0), R_VN);
      const int samples = std::max(4096, static_cast<int>(length / 0.002));
      ExpectMatchesBruteForce(c, samples);
      if (::testing::Test::HasFailure()) return;
    }
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
    EXPECT_THROW(ValidateArcTorus(c.arc, c.torus), std::invalid_argument) << what;
  };
  EXPECT_NO_THROW(ValidateArcTorus(good.arc, good.torus));
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
    EXPECT_LT((X * a.p_WD - b.p_WD).norm(), 1e-6 * c.torus.core_radius_m) << i;
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
    // p_WD is the needle point at s_rad, inside the azimuth range.
    const Eigen::Vector3d p_N(c.arc.radius_m * std::cos(out.s_rad),
                              c.arc.radius_m * std::sin(out.s_rad), 0);
    EXPECT_LT((c.arc.X_WN * p_N - out.p_WD).norm(), tol);
    EXPECT_GE(out.s_rad, 0);
    EXPECT_LE(out.s_rad, c.arc.sweep_rad);
    const Eigen::Vector3d p_V = c.torus.X_WV.inverse() * out.p_WD;
    const double omega = c.torus.segment_angle_rad;
    const bool on_end_plane = std::abs(p_V.y()) < tol ||
                              std::abs(p_V.x() * std::sin(omega) - p_V.y() * std::cos(omega)) < tol;
    EXPECT_TRUE(IsAzimuthInSegment(p_V.x(), p_V.y(), omega) || on_end_plane);
    // p_WB is on the wall, at distance |clearance| from p_WD.
    const Eigen::Vector3d w_V = c.torus.X_WV.inverse() * out.p_WB;
    EXPECT_NEAR(std::hypot(w_V.head<2>().norm() - R, w_V.z()), r, tol);
    EXPECT_NEAR((out.p_WB - out.p_WD).norm(), std::abs(out.clearance_m), tol);
  }
}

}  // namespace
}  // namespace microdex::geometry
