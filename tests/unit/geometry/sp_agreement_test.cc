// The SP method against the exact method: touch / no-touch agreement and clearance error on
// a million random configurations and on an adversarial set built around the degenerate
// cases, and invariance under rigid motions and uniform scaling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/arc_torus_sp.h"
#include "tests/unit/geometry/brute_force_clearance.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry {
namespace {

using testing::RandomArcTorus;
using testing::RandomRotation;

constexpr double kPi = std::numbers::pi;
// Touch / no-touch must agree wherever the exact clearance is farther than this from 0.
constexpr double kContactBandRel = 1e-9;
// SP's clearance against the exact one, relative to R.
constexpr double kClearanceRelTol = 1e-10;

#ifdef NDEBUG
constexpr int kRandomCases = 1'000'000;
constexpr int kSmallSetCases = 60'000;
#else
// Unoptimised (and sanitizer) builds: the same checks on fewer cases.
constexpr int kRandomCases = 50'000;
constexpr int kSmallSetCases = 6'000;
#endif

struct Stats {
  long cases = 0, ok = 0, disagreements = 0, empty = 0;
  double max_error_rel = 0;  // max |SP − reference| / R
  // Cases where the exact method was the one off (the brute force sided with SP).
  long exact_off = 0;
  double max_exact_off_rel = 0;
  void Add(const RandomArcTorus& c) {
    const ArcTorusClearance sp = CalcArcTorusClearanceSP(c.arc, c.torus);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    ++cases;
    ASSERT_EQ(sp.status, exact.status) << Describe(c);
    if (sp.status == ClearanceStatus::kEmptyRange) ++empty;
    if (sp.status != ClearanceStatus::kOk) return;
    ++ok;
    const double R = c.torus.core_radius_m;
    if (std::abs(exact.clearance_m) > kContactBandRel * R && sp.contact != exact.contact) {
      ++disagreements;
      ADD_FAILURE() << "contact disagrees: " << Describe(c) << " sp " << sp.clearance_m << " exact "
                    << exact.clearance_m;
    }
    double err = std::abs(sp.clearance_m - exact.clearance_m) / R;
    if (err > kClearanceRelTol) {
      // Arbitrate with the long-double brute force (independent of both methods).
      const double brute = static_cast<double>(
          testing::CalcArcTorusClearanceBruteForce(c.arc, c.torus, 8192).clearance_m);
      const double err_brute = std::abs(sp.clearance_m - brute) / R;
      if (err_brute <= kClearanceRelTol) {
        // The exact method is the reference: it being off is a failure too.
        ++exact_off;
        max_exact_off_rel = std::max(max_exact_off_rel, std::abs(exact.clearance_m - brute) / R);
        ADD_FAILURE() << "exact method off the brute force by "
                      << std::abs(exact.clearance_m - brute) / R
                      << " R (SP agrees with it): " << Describe(c) << " sp " << sp.clearance_m
                      << " exact " << exact.clearance_m << " brute force " << brute;
        err = err_brute;
      } else {
        ADD_FAILURE() << "clearance differs by " << err << " R: " << Describe(c) << " sp "
                      << sp.clearance_m << " (s " << sp.s_rad << ") exact " << exact.clearance_m
                      << " (s " << exact.s_rad << ") brute force " << brute;
      }
    }
    max_error_rel = std::max(max_error_rel, err);
  }
  // Every input to 17 digits, so that a reported case can be replayed.
  static std::string Describe(const RandomArcTorus& c) {
    char buf[256];
    std::snprintf(buf, sizeof(buf), "R %.17g r %.17g rho %.17g sweep %.17g omega %.17g",
                  c.torus.core_radius_m, c.torus.tube_radius_m, c.arc.radius_m, c.arc.sweep_rad,
                  c.torus.segment_angle_rad);
    std::string out = buf;
    for (const Eigen::Isometry3d* X : {&c.arc.X_WN, &c.torus.X_WV}) {
      out += X == &c.arc.X_WN ? " X_WN" : " X_WV";
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 4; ++j) {
          std::snprintf(buf, sizeof(buf), " %.17g", X->matrix()(i, j));
          out += buf;
        }
      }
    }
    return out;
  }
  void Print(const char* name) const {
    std::printf(
        "[ %s ] cases %ld, ok %ld, empty %ld, contact disagreements %ld, max |SP - reference| "
        "= %.3g R; exact off the brute force (which sided with SP) in %ld cases, max %.3g R\n",
        name, cases, ok, empty, disagreements, max_error_rel, exact_off, max_exact_off_rel);
  }
};

// The needle pose from its pose in the vessel frame.
void Place(RandomArcTorus* c, const Eigen::Vector3d& center_V, const Eigen::Matrix3d& R_VN) {
  Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
  X_VN.linear() = R_VN;
  X_VN.translation() = center_V;
  c->arc.X_WN = c->torus.X_WV * X_VN;
}

Eigen::Isometry3d RandomPose(std::mt19937_64& rng, double translation_m) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = RandomRotation(rng).toRotationMatrix();
  X.translation() = translation_m * Eigen::Vector3d(u(rng), u(rng), u(rng));
  return X;
}

// A vessel of training size (R 2–10 mm, r/R 0.03–0.53), half of them a segment.
RandomArcTorus RandomVessel(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  RandomArcTorus c;
  c.torus.core_radius_m = 2e-3 + 8e-3 * u(rng);
  c.torus.tube_radius_m = (0.03 + 0.5 * u(rng)) * c.torus.core_radius_m;
  c.torus.segment_angle_rad = u(rng) < 0.5 ? 2 * kPi : 0.2 + (2 * kPi - 0.2) * u(rng);
  c.torus.X_WV = RandomPose(rng, 0.05);
  return c;
}

// Crossing: the needle passes through a random point at 0.7–1.3 r from the core circle, in
// a random direction.
RandomArcTorus MakeCrossing(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  RandomArcTorus c = RandomVessel(rng);
  const double R = c.torus.core_radius_m, r = c.torus.tube_radius_m;
  c.arc.radius_m = R * (0.2 + 1.5 * u(rng));
  c.arc.sweep_rad = 0.05 + (2 * kPi - 0.05) * u(rng);
  const double phi = 2 * kPi * u(rng), psi = 2 * kPi * u(rng), rr = r * (0.7 + 0.6 * u(rng));
  const Eigen::Vector3d q((R + rr * std::cos(psi)) * std::cos(phi),
                          (R + rr * std::cos(psi)) * std::sin(phi), rr * std::sin(psi));
  const Eigen::Matrix3d R_VN = RandomRotation(rng).toRotationMatrix();
  const double s0 = c.arc.sweep_rad * u(rng);
  Place(&c,
        q - R_VN * Eigen::Vector3d(c.arc.radius_m * std::cos(s0), c.arc.radius_m * std::sin(s0), 0),
        R_VN);
  return c;
}

// Near the ideal path with larger deviations than MakeNearCoreArcTorus: offsets ~ r/2, tilts
// ~ r/(2R), needle radius R(1 ± 0.3 r/R).
RandomArcTorus MakeNearIdeal(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n;
  RandomArcTorus c = RandomVessel(rng);
  const double R = c.torus.core_radius_m, r = c.torus.tube_radius_m;
  c.arc.radius_m = R * (1 + 0.3 * (r / R) * n(rng));
  c.arc.sweep_rad = 0.2 + (2 * kPi - 0.2) * u(rng);
  const Eigen::Vector3d axis = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  const Eigen::Matrix3d R_VN = (Eigen::AngleAxisd(0.5 * (r / R) * std::abs(n(rng)), axis) *
                                Eigen::AngleAxisd(2 * kPi * u(rng), Eigen::Vector3d::UnitZ()))
                                   .toRotationMatrix();
  Place(&c, 0.5 * r * Eigen::Vector3d(n(rng), n(rng), n(rng)), R_VN);
  return c;
}

TEST(SpAgreementTest, MillionRandomConfigurations) {
  std::mt19937_64 rng(20260101);
  Stats near_ideal, crossing, near_core, wide;
  for (int i = 0; i < kRandomCases; ++i) {
    switch (i % 4) {
      case 0:
        near_ideal.Add(MakeNearIdeal(rng));
        break;
      case 1:
        crossing.Add(MakeCrossing(rng));
        break;
      case 2:
        near_core.Add(testing::MakeNearCoreArcTorus(rng));
        break;
      default:
        wide.Add(testing::MakeWideArcTorus(rng));
        break;
    }
    if (HasFatalFailure() || ::testing::Test::HasFailure()) break;
  }
  near_ideal.Print("near ideal path");
  crossing.Print("crossing the wall");
  near_core.Print("near core (shared generator)");
  wide.Print("wide (shared generator)");
  EXPECT_EQ(near_ideal.cases + crossing.cases + near_core.cases + wide.cases, kRandomCases);
  // The figures README.md states (its "needle–vessel clearance" row), as bounds.
  EXPECT_LE(std::max({near_ideal.max_error_rel, crossing.max_error_rel, near_core.max_error_rel}),
            3e-14);
  EXPECT_LE(wide.max_error_rel, 3e-13);
}

// Degenerate families, each exactly and under perturbations from 1e-15 to 1e-3 (relative).
TEST(SpAgreementTest, AdversarialSet) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n;
  const double kEps[] = {0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3};
  Stats stats;
  const auto random_dir = [&] { return Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized(); };
  const auto turn = [&](double angle) {
    return Eigen::AngleAxisd(angle, random_dir()).toRotationMatrix();
  };
  for (int rep = 0; rep < 60; ++rep) {
    for (const double eps : kEps) {
      RandomArcTorus base = RandomVessel(rng);
      const double R = base.torus.core_radius_m, r = base.torus.tube_radius_m;
      const Eigen::Matrix3d spin =
          Eigen::AngleAxisd(2 * kPi * u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      base.arc.sweep_rad = 0.1 + (2 * kPi - 0.1) * u(rng);
      // On the core circle (the ideal path).
      RandomArcTorus c = base;
      c.arc.radius_m = R * (1 + eps * n(rng));
      Place(&c, eps * R * random_dir(), turn(eps) * spin);
      stats.Add(c);
      // Coplanar with the core circle: centre and radius anywhere in the core plane.
      c = base;
      c.arc.radius_m = R * (0.2 + 1.5 * u(rng));
      Place(&c, Eigen::Vector3d(R * (u(rng) - 0.5), R * (u(rng) - 0.5), eps * R * n(rng)),
            turn(eps) * spin);
      stats.Add(c);
      // Concentric with it, at a height, slightly tilted.
      c = base;
      c.arc.radius_m = R + r * (u(rng) - 0.5);
      Place(&c, Eigen::Vector3d(eps * R * n(rng), eps * R * n(rng), r * (u(rng) - 0.5)),
            turn(eps) * spin);
      stats.Add(c);
      // In a meridian plane (through the z axis): through the hole or around the tube.
      c = base;
      c.arc.radius_m = u(rng) < 0.5 ? r * (0.3 + u(rng)) : R * (0.3 + u(rng));
      Place(&c, spin * Eigen::Vector3d(R * u(rng), 0, r * (u(rng) - 0.5)),
            turn(eps) * spin *
                Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
      stats.Add(c);
      // A Villarceau circle of the tube (on the wall).
      c = base;
      c.arc.radius_m = R * (1 + eps * n(rng));
      Place(&c, spin * Eigen::Vector3d(r, 0, 0) + eps * R * random_dir(),
            turn(eps) * spin *
                Eigen::AngleAxisd(std::asin(r / R), Eigen::Vector3d::UnitX()).toRotationMatrix());
      stats.Add(c);
      // Sweep → 0 and → 2π, on a generic near-ideal pose.
      for (const double sweep : {1e-9 + eps, 2 * kPi - eps}) {
        c = MakeNearIdeal(rng);
        c.arc.sweep_rad = sweep;
        stats.Add(c);
      }
      // ρ ≪ R and ρ ≫ R through the wall.
      for (const double rho_rel : {1e-5, 1e-3, 30.0, 1e3}) {
        c = base;
        c.arc.radius_m = rho_rel * R;
        const Eigen::Vector3d q = spin * Eigen::Vector3d(R + r * (1 + eps), 0, 0);
        const Eigen::Matrix3d R_VN = RandomRotation(rng).toRotationMatrix();
        Place(&c, q - R_VN * Eigen::Vector3d(c.arc.radius_m, 0, 0) * (1 - 1e-3 * u(rng)), R_VN);
        stats.Add(c);
      }
      // r → 0 and r → R.
      for (const double beta : {1e-6, 1e-3, 0.99, 1 - 1e-5}) {
        c = MakeNearIdeal(rng);
        c.torus.tube_radius_m = beta * c.torus.core_radius_m;
        stats.Add(c);
      }
      // The needle lying in a boundary plane of the segment (y = 0).
      c = base;
      c.torus.segment_angle_rad = 0.3 + 5 * u(rng);
      c.arc.radius_m = R * (0.5 + u(rng));
      Place(&c, Eigen::Vector3d(R * u(rng), eps * R * n(rng), r * (u(rng) - 0.5)),
            turn(eps) * Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
      stats.Add(c);
      if (::testing::Test::HasFailure()) break;
    }
  }
  stats.Print("adversarial");
  EXPECT_EQ(stats.cases, 5760);
  EXPECT_LE(stats.max_error_rel, 1e-10);  // README.md: 6.0e-11 R (ρ = 1e3 R needles)
}

// Touch / no-touch is exact for every setting, including the thesis's single pass (no
// distance refinement, no certificate) with a loose Newton tolerance on (4.26).
TEST(SpAgreementTest, EverySettingClassifiesLikeTheExactMethod) {
  SpOptions thesis_loose;
  thesis_loose.quartic_method = SpQuarticMethod::kNewton;
  thesis_loose.quartic_tol = 1e-6;
  thesis_loose.polish_max_iters = 0;
  thesis_loose.max_certify_rounds = 0;
  SpOptions closed_single = thesis_loose;
  closed_single.quartic_method = SpQuarticMethod::kClosedForm;
  SpOptions refined_single;
  refined_single.max_certify_rounds = 0;
  std::mt19937_64 rng(5150);
  long checked = 0;
  for (int i = 0; i < kSmallSetCases; ++i) {
    const RandomArcTorus c = i % 2 == 0 ? MakeNearIdeal(rng) : MakeCrossing(rng);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    if (exact.status != ClearanceStatus::kOk ||
        std::abs(exact.clearance_m) <= kContactBandRel * c.torus.core_radius_m) {
      continue;
    }
    ++checked;
    for (const SpOptions& o : {thesis_loose, closed_single, refined_single}) {
      const ArcTorusClearance sp = CalcArcTorusClearanceSP(c.arc, c.torus, o);
      ASSERT_EQ(sp.contact, exact.contact) << i << " " << Stats::Describe(c);
    }
  }
  EXPECT_GT(checked, kSmallSetCases * 8 / 10);
}

// The certificate's quick test (no quartic) only proves what the full pass would confirm:
// with it and without it the answer is the same, also where the full pass finds a farther
// point than the ascent (a second local maximum), and the quick test is what settles most
// training-like queries.
TEST(SpAgreementTest, QuickCertificateAgreesWithTheFullPass) {
  SpOptions full;
  full.quick_certificate = false;
  std::mt19937_64 rng(4242);
  long ok = 0, settled_quick = 0, near_core = 0, farther_found = 0;
  double max_diff_rel = 0;
  for (int i = 0; i < kSmallSetCases; ++i) {
    const RandomArcTorus c =
        i % 3 == 0 ? MakeNearIdeal(rng)
                   : (i % 3 == 1 ? MakeCrossing(rng) : testing::MakeNearCoreArcTorus(rng));
    const ArcTorusClearance quick = CalcArcTorusClearanceSP(c.arc, c.torus);
    const ArcTorusClearance slow = CalcArcTorusClearanceSP(c.arc, c.torus, full);
    ASSERT_EQ(quick.status, slow.status) << Stats::Describe(c);
    if (quick.status != ClearanceStatus::kOk) continue;
    ++ok;
    const double diff = std::abs(quick.clearance_m - slow.clearance_m) / c.torus.core_radius_m;
    EXPECT_LE(diff, 1e-13) << Stats::Describe(c);
    max_diff_rel = std::max(max_diff_rel, diff);
    SpDiagnostics dq, ds;
    CalcArcTorusClearanceSP(c.arc, c.torus, SpOptions{}, &dq);
    CalcArcTorusClearanceSP(c.arc, c.torus, full, &ds);
    farther_found += ds.certify_improvements > 0;
    if (i % 3 != 1) {
      ++near_core;
      settled_quick += dq.certify_quick > 0;
    }
    if (::testing::Test::HasFailure()) break;
  }
  std::printf(
      "[ quick certificate ] cases %ld, max |quick - full| = %.3g R, full pass found a farther "
      "point in %ld, quick test settled %ld of %ld near-core\n",
      ok, max_diff_rel, farther_found, settled_quick, near_core);
  EXPECT_GT(settled_quick, near_core / 2);
  EXPECT_LE(max_diff_rel, 1e-14);  // README_sp.md: 7.7e-15 R
}

// Deep contacts (the deepest point R or more from the core circle): the level sets there are
// spindle tori, which the lifted quadric (4.4) cannot express, but the certificate along the
// needle handles them itself (outside the spindle's inner lemon; README_sp.md), so that the
// exact method answers only a few up to 10·R — and SP's answers agree with it (with the
// long-double brute force as arbiter, as above). Farther out, G̃_t's precision no longer
// bounds the error well enough and more of them go to the exact method (printed).
TEST(SpAgreementTest, DeepContactsAreCertifiedBySp) {
  std::mt19937_64 rng(777);
  Stats deep;
  long within_10r = 0, by_exact = 0, by_exact_within_10r = 0;
  for (int i = 0; i < kSmallSetCases; ++i) {
    const RandomArcTorus c = i % 2 == 0 ? MakeCrossing(rng) : testing::MakeWideArcTorus(rng);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    const double R = c.torus.core_radius_m;
    const double t = c.torus.tube_radius_m - exact.clearance_m;
    if (exact.status != ClearanceStatus::kOk || t < R) continue;
    deep.Add(c);
    SpDiagnostics diag;
    const ArcTorusClearance sp = CalcArcTorusClearanceSP(c.arc, c.torus, SpOptions{}, &diag);
    EXPECT_NEAR(sp.clearance_m, exact.clearance_m, kClearanceRelTol * R) << Stats::Describe(c);
    by_exact += diag.deep_fallback();
    if (t < 10 * R) {
      ++within_10r;
      by_exact_within_10r += diag.deep_fallback();
    }
    if (::testing::Test::HasFailure()) break;
  }
  deep.Print("deep contacts");
  std::printf(
      "[ deep contacts ] answered by the exact method: %ld of %ld, of those within 10 R: %ld of "
      "%ld\n",
      by_exact, deep.ok, by_exact_within_10r, within_10r);
  EXPECT_GT(within_10r, kSmallSetCases / 4);
  EXPECT_LT(by_exact_within_10r, within_10r / 50);
  EXPECT_LE(deep.max_error_rel, 1e-13);  // README_sp.md: 8.5e-14 R
}

TEST(SpAgreementTest, InvariantUnderRigidMotionAndUniformScaling) {
  std::mt19937_64 rng(99);
  double max_rigid = 0, max_scale = 0;
  for (int i = 0; i < kSmallSetCases / 3; ++i) {
    const RandomArcTorus c =
        i % 3 == 0 ? MakeNearIdeal(rng)
                   : (i % 3 == 1 ? MakeCrossing(rng) : testing::MakeWideArcTorus(rng));
    const double R = c.torus.core_radius_m;
    const ArcTorusClearance base = CalcArcTorusClearanceSP(c.arc, c.torus);
    // Both frames moved together, up to 1e3·R away.
    const Eigen::Isometry3d X = RandomPose(rng, 1e3 * R);
    RandomArcTorus moved = c;
    moved.arc.X_WN = X * c.arc.X_WN;
    moved.torus.X_WV = X * c.torus.X_WV;
    const ArcTorusClearance m = CalcArcTorusClearanceSP(moved.arc, moved.torus);
    ASSERT_EQ(m.status, base.status);
    if (base.status == ClearanceStatus::kOk) {
      const double err = std::abs(m.clearance_m - base.clearance_m) / R;
      EXPECT_LE(err, kClearanceRelTol) << i;
      if (std::abs(base.clearance_m) > kContactBandRel * R) {
        EXPECT_EQ(m.contact, base.contact);
      }
      max_rigid = std::max(max_rigid, err);
    }
    // Every length scaled by k (the micrometre scale and up).
    for (const double k : {1e-6, 1e-3, 1e3}) {
      const RandomArcTorus s = testing::Transformed(c, Eigen::Isometry3d::Identity(), k);
      const ArcTorusClearance sc = CalcArcTorusClearanceSP(s.arc, s.torus);
      ASSERT_EQ(sc.status, base.status);
      if (base.status != ClearanceStatus::kOk) continue;
      const double err = std::abs(sc.clearance_m / k - base.clearance_m) / R;
      EXPECT_LE(err, kClearanceRelTol) << i << " k " << k;
      max_scale = std::max(max_scale, err);
    }
    if (::testing::Test::HasFailure()) break;
  }
  std::printf("[ invariance ] max change under rigid motion %.3g R, under scaling %.3g R\n",
              max_rigid, max_scale);
}

}  // namespace
}  // namespace microdex::geometry
