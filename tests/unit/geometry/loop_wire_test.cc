// The loop-along-a-wire clearance (loop_wire.h) against an independent long-double brute force
// (loop_wire_reference.cc), analytic configurations, invariants, the Defs' validation and the
// progress query.
#include "common/geometry/loop_wire.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/loop_wire_arc.h"
#include "common/geometry/loop_wire_segment.h"
#include "tests/support/alloc_counter.h"
#include "tests/unit/geometry/loop_wire_reference.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
// Agreement with the reference, relative to R, plus the rounding of the inputs' coordinates
// (relative to their size: a loop 1 km away cannot be placed to better than ~1e-13 m).
constexpr double kAgreeRel = 1e-12;
constexpr double kCoordRel = 1e-15;

using testing::CalcLoopWireReference;
using testing::RandomLoopWire;

double Tolerance_m(const LoopDef& loop, const WireDef& wire, const Eigen::Isometry3d& X_WL) {
  double coord = X_WL.translation().norm();
  for (const WirePieceDef& p : wire.pieces) {
    coord = std::max({coord, p.StartPoint().norm(), p.EndPoint().norm(), p.p_WO.norm()});
  }
  return kAgreeRel * loop.radius_m + kCoordRel * coord;
}

// Checks the query against the reference, and the consistency of its closest points.
void ExpectAgreesWithReference(const LoopDef& loop, const WireDef& wire,
                               const Eigen::Isometry3d& X_WL, const std::string& what) {
  const LoopWireModel model(loop, wire);
  const LoopWireClearance c = CalcLoopWireClearance(model, X_WL);
  const testing::LoopWireReference ref = CalcLoopWireReference(loop, wire, X_WL);
  const double tol = Tolerance_m(loop, wire, X_WL);
  ASSERT_EQ(c.status, LoopWireStatus::kOk) << what;
  EXPECT_NEAR(c.distance_m, static_cast<double>(ref.distance_m), tol) << what;
  EXPECT_NEAR(c.clearance_m, c.distance_m - loop.wire_radius_m - wire.radius_m,
              1e-15 * loop.radius_m)
      << what;
  EXPECT_EQ(c.contact, c.clearance_m <= 0) << what;
  // A on the wire's axis, C on the loop's circle, |A − C| the distance.
  EXPECT_NEAR((c.p_WA - c.p_WC).norm(), c.distance_m, 4 * tol) << what;
  const Eigen::Vector3d p_LC = X_WL.inverse() * c.p_WC;
  EXPECT_NEAR(std::hypot(p_LC.x(), p_LC.y()), loop.radius_m, 4 * tol) << what;
  EXPECT_NEAR(p_LC.z(), 0, 4 * tol) << what;
  const WireProgress at_a = CalcWireProgress(model, c.p_WA);
  EXPECT_NEAR(at_a.distance_m, 0, 4 * tol) << what;
}

// ---- Validation -----------------------------------------------------------------------------

void ExpectInvalid(const WireDef& wire, const std::string& field_prefix) {
  try {
    wire.Validate();
    ADD_FAILURE() << "no exception, expected " << field_prefix;
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind(field_prefix, 0), 0u) << e.what();
  }
}

WireDef TwoPieceWire() {
  WireDef w;
  w.pieces.push_back(WirePieceDef::Segment({0, 0, 0}, {0.01, 0, 0}));
  w.pieces.push_back(WirePieceDef::Arc({0.01, 0.005, 0}, {0, 0, 1}, {0, -1, 0}, 0.005, kPi / 2));
  return w;
}

TEST(LoopWireDefs, ValidCoursePasses) {
  EXPECT_NO_THROW(TwoPieceWire().Validate());
  EXPECT_NO_THROW(LoopDef{}.Validate());
}

TEST(LoopWireDefs, ZeroLengthAndBadPiecesAreRejectedNamingTheField) {
  WireDef w = TwoPieceWire();
  w.pieces[0].p_W1 = w.pieces[0].p_W0;  // zero-length segment
  w.pieces[1].p_WO = {0, 0.005, 0};
  ExpectInvalid(w, "WireDef.pieces[0].p_W1");
  w = TwoPieceWire();
  w.pieces[1].sweep_rad = 0;
  ExpectInvalid(w, "WireDef.pieces[1].sweep_rad");
  w.pieces[1].sweep_rad = 1e-14;  // zero length to the course's extent
  ExpectInvalid(w, "WireDef.pieces[1].sweep_rad");
  w.pieces[1].sweep_rad = 2 * kPi + 1e-9;
  ExpectInvalid(w, "WireDef.pieces[1].sweep_rad");
  w = TwoPieceWire();
  w.pieces[1].radius_m = 0;
  ExpectInvalid(w, "WireDef.pieces[1].radius_m");
  w = TwoPieceWire();
  w.pieces[1].axis_W = {0, 0, 2};
  ExpectInvalid(w, "WireDef.pieces[1].axis_W");
  w = TwoPieceWire();
  w.pieces[1].u_W = Eigen::Vector3d(0, -1, 1).normalized();
  ExpectInvalid(w, "WireDef.pieces[1].u_W");
  w = TwoPieceWire();
  w.pieces[1].p_WO.x() += 1e-6;  // a gap at the join
  ExpectInvalid(w, "WireDef.pieces[1].p_WO");
  w = TwoPieceWire();
  w.pieces[0].p_W0.x() = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(w, "WireDef.pieces[0].p_W0");
  w = TwoPieceWire();
  w.radius_m = 0;
  ExpectInvalid(w, "WireDef.radius_m");
  ExpectInvalid(WireDef{}, "WireDef.pieces");
}

TEST(LoopWireDefs, LoopDefIsValidated) {
  const auto expect = [](LoopDef d, const std::string& field) {
    try {
      d.Validate();
      ADD_FAILURE() << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field, 0), 0u) << e.what();
    }
  };
  expect({0, 1e-4}, "LoopDef.radius_m");
  expect({-1, 1e-4}, "LoopDef.radius_m");
  expect({1e-3, 0}, "LoopDef.wire_radius_m");
  expect({1e-3, 1e-3}, "LoopDef.wire_radius_m");
  expect({std::numeric_limits<double>::infinity(), 1e-4}, "LoopDef.radius_m");
  EXPECT_THROW(LoopWireModel(LoopDef{0, 1}, TwoPieceWire()), std::invalid_argument);
}

TEST(LoopWireDefs, CourseBuilderJoinsPiecesAndTurnsInItsPlanes) {
  const double R = 2e-3;
  const std::vector<WireCourseStepDef> steps = {
      WireCourseStepDef::Straight(3 * R), WireCourseStepDef::Turn(2 * R, kPi / 2, 0),
      WireCourseStepDef::Straight(R), WireCourseStepDef::Turn(R, kPi / 2, kPi / 2),
      WireCourseStepDef::Turn(3 * R, kPi, -kPi / 3)};
  const WireDef w = MakeWireCourse(Eigen::Isometry3d::Identity(), steps, 1e-4);
  ASSERT_EQ(w.pieces.size(), 5u);
  // First turn towards +y (the start frame's normal): ends at (3R + 2R, 2R, 0) heading +y.
  EXPECT_NEAR((w.pieces[1].EndPoint() - Eigen::Vector3d(5 * R, 2 * R, 0)).norm(), 0, 1e-15);
  // Straight R along +y, then a turn towards the binormal (t × n = +y × −x = +z).
  EXPECT_NEAR((w.pieces[2].EndPoint() - Eigen::Vector3d(5 * R, 3 * R, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((w.pieces[3].EndPoint() - Eigen::Vector3d(5 * R, 4 * R, R)).norm(), 0, 1e-15);
  const LoopWireModel model(LoopDef{R, 1e-4}, w);
  EXPECT_NEAR(model.length_m(), 3 * R + kPi * R + R + kPi / 2 * R + 3 * kPi * R, 1e-15);
  EXPECT_THROW(
      MakeWireCourse(Eigen::Isometry3d::Identity(), {WireCourseStepDef::Straight(0)}, 1e-4),
      std::invalid_argument);
  EXPECT_THROW(MakeWireCourse(Eigen::Isometry3d::Identity(), {WireCourseStepDef::Turn(0, 1)}, 1e-4),
               std::invalid_argument);
}

TEST(LoopWireQuery, InvalidPoseIsAStatusNotAnException) {
  const LoopWireModel model(LoopDef{}, TwoPieceWire());
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(CalcLoopWireClearance(model, X).status, LoopWireStatus::kInvalidPose);
  EXPECT_TRUE(std::isnan(CalcLoopWireClearance(model, X).clearance_m));
  X = Eigen::Isometry3d::Identity();
  X.linear() *= 1.01;
  EXPECT_EQ(CalcLoopWireClearance(model, X).status, LoopWireStatus::kInvalidPose);
  EXPECT_EQ(CalcWireProgress(model, {std::nan(""), 0, 0}).status, LoopWireStatus::kInvalidPose);
}

// ---- Random courses against the reference ---------------------------------------------------

TEST(LoopWireQuery, RandomCoursesAgreeWithLongDoubleBruteForce) {
  std::mt19937_64 rng(1234);
  int contacts = 0, queries = 0;
  for (int course = 0; course < 60; ++course) {
    const RandomLoopWire s = testing::MakeRandomLoopWire(rng, 2e-3);
    for (int k = 0; k < 30; ++k) {
      const Eigen::Isometry3d X_WL = k % 3 == 2 ? testing::MakeWidePose(rng, s, 4e-3)
                                                : testing::MakeThreadedPose(rng, s, 2e-3, kPi / 3);
      ExpectAgreesWithReference(s.loop, s.wire, X_WL,
                                "course " + std::to_string(course) + " pose " + std::to_string(k));
      const LoopWireModel model(s.loop, s.wire);
      contacts += CalcLoopWireClearance(model, X_WL).contact;
      ++queries;
    }
  }
  // Both sides of contact are exercised.
  EXPECT_GT(contacts, queries / 10);
  EXPECT_LT(contacts, queries * 9 / 10);
}

TEST(LoopWireQuery, LoopAndWireRadiiSweep) {
  std::mt19937_64 rng(77);
  for (const double R : {0.2e-3, 1e-3, 5e-3, 20e-3}) {
    for (const double r_w : {10e-6, 100e-6, 1e-3}) {
      for (int course = 0; course < 4; ++course) {
        RandomLoopWire s = testing::MakeRandomLoopWire(rng, R);
        s.wire.radius_m = r_w;
        s.loop.wire_radius_m = std::min(0.5 * R, std::max(10e-6, 0.1 * R));
        for (int k = 0; k < 6; ++k) {
          ExpectAgreesWithReference(s.loop, s.wire, testing::MakeThreadedPose(rng, s, R, kPi / 3),
                                    "R " + std::to_string(R) + " r_w " + std::to_string(r_w));
        }
      }
    }
  }
}

// ---- Invariants -----------------------------------------------------------------------------

WireDef Transformed(const WireDef& w, const Eigen::Isometry3d& X, double scale) {
  WireDef out = w;
  out.radius_m *= scale;
  for (WirePieceDef& p : out.pieces) {
    p.p_W0 = X * (scale * p.p_W0);
    p.p_W1 = X * (scale * p.p_W1);
    p.p_WO = X * (scale * p.p_WO);
    p.axis_W = X.linear() * p.axis_W;
    p.u_W = X.linear() * p.u_W;
    p.radius_m *= scale;
  }
  return out;
}

TEST(LoopWireQuery, RigidMotionAndScalingOfBoth) {
  std::mt19937_64 rng(5);
  for (int course = 0; course < 40; ++course) {
    const RandomLoopWire s = testing::MakeRandomLoopWire(rng, 3e-3);
    const LoopWireModel model(s.loop, s.wire);
    for (int k = 0; k < 10; ++k) {
      const Eigen::Isometry3d X_WL = testing::MakeThreadedPose(rng, s, 3e-3, kPi / 3);
      const LoopWireClearance c = CalcLoopWireClearance(model, X_WL);
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.linear() = testing::RandomRotation(rng).toRotationMatrix();
      X.translation() = Eigen::Vector3d::Random() * 0.05;
      const LoopWireModel moved(s.loop, Transformed(s.wire, X, 1));
      const LoopWireClearance cm = CalcLoopWireClearance(moved, X * X_WL);
      EXPECT_NEAR(cm.clearance_m, c.clearance_m, Tolerance_m(s.loop, s.wire, X_WL) + 1e-15 * 0.1);
      EXPECT_EQ(cm.piece, c.piece);
      for (const double scale : {1e-3, 7.0, 1e3}) {
        const LoopDef loop{s.loop.radius_m * scale, s.loop.wire_radius_m * scale};
        const LoopWireModel scaled(loop, Transformed(s.wire, Eigen::Isometry3d::Identity(), scale));
        Eigen::Isometry3d X_scaled = X_WL;
        X_scaled.translation() *= scale;
        const LoopWireClearance cs = CalcLoopWireClearance(scaled, X_scaled);
        EXPECT_NEAR(cs.clearance_m, scale * c.clearance_m,
                    scale * Tolerance_m(s.loop, s.wire, X_WL));
      }
    }
  }
}

// ---- Analytic configurations ----------------------------------------------------------------

WireDef SegmentWire(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r_w) {
  WireDef w;
  w.pieces.push_back(WirePieceDef::Segment(a, b));
  w.radius_m = r_w;
  return w;
}

TEST(LoopWireAnalytic, WireAlongTheLoopsAxisIsRAwayFromEveryCirclePoint) {
  for (const double R : {0.2e-3, 2e-3, 20e-3}) {
    const LoopDef loop{R, 0.1 * R};
    // Through the centre, along the axis, symmetric and not.
    for (const double z0 : {-5.0, -1.0, -1e-9}) {
      const WireDef w = SegmentWire({0, 0, z0 * R}, {0, 0, 3 * R}, 10e-6);
      const LoopWireModel model(loop, w);
      const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
      EXPECT_NEAR(c.distance_m, R, 1e-15 * R);
      // F = R² + z² is flat at z = 0: the point is located to √ε R only.
      EXPECT_NEAR(c.p_WA.norm(), 0, 1.5e-8 * R);
      EXPECT_NEAR(c.p_WC.norm(), R, 1e-15 * R);
    }
    // Beside the axis, parallel to it: |h − R|, on the circle too.
    for (const double h : {0.0, 1e-12, 1e-6, 0.5, 1 - 1e-12, 1.0, 1 + 1e-9, 3.0}) {
      const WireDef w = SegmentWire({h * R, 0, -2 * R}, {h * R, 0, 2 * R}, 10e-6);
      const LoopWireModel model(loop, w);
      const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
      EXPECT_NEAR(c.distance_m, std::abs(h - 1) * R, 1e-15 * R) << h;
    }
  }
}

TEST(LoopWireAnalytic, WireInTheLoopsPlane) {
  const double R = 1e-3;
  const LoopDef loop{R, 0.1 * R};
  // A chord at height h from the centre: crosses the circle (distance 0) when h < R, else
  // h − R at the double root of the squared quartic.
  for (const double h : {0.0, 0.3, 1 - 1e-9, 1.0, 1 + 1e-12, 1 + 1e-9, 1 + 1e-6, 1.5, 40.0}) {
    const WireDef w = SegmentWire({-50 * R, h * R, 0}, {50 * R, h * R, 0}, 10e-6);
    const LoopWireModel model(loop, w);
    const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
    EXPECT_NEAR(c.distance_m, std::max(0.0, h - 1) * R, 2e-15 * R * std::max(1.0, h)) << h;
    const LoopWirePieceMin q = CalcSegmentCircleMinQuartic({-50, h, 0}, {50, h, 0});
    RecordProperty("quartic_error_in_plane_h" + std::to_string(h),
                   std::to_string(std::sqrt(q.dist_sq) - std::max(0.0, h - 1)));
  }
}

TEST(LoopWireAnalytic, NearTangentChordsInAnyDirection) {
  // As above, turned about the axis, so that the line's point nearest the centre is ⊥ to its
  // direction only to rounding: the distance h − R is a minimum of F as flat as h − R is
  // small. (Once off by up to 7e-11 R, when the slope of F was formed as p·d − k'.)
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  const LoopDef loop{1e-3, 0.1e-3};
  for (int i = 0; i < 300; ++i) {
    const double h = 1 + std::pow(10.0, -12 + 5 * (u(rng) + 1)), phi = kPi * u(rng);
    const double tilt = i % 2 ? 0 : std::pow(10.0, -12 + 4.5 * (u(rng) + 1));
    const Eigen::Vector3d n(std::cos(phi), std::sin(phi), 0);
    const Eigen::Vector3d t = std::cos(tilt) * Eigen::Vector3d(-n.y(), n.x(), 0) +
                              std::sin(tilt) * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d p = h * loop.radius_m * n;
    ExpectAgreesWithReference(
        loop, SegmentWire(p - (2 + u(rng)) * 1e-3 * t, p + (2 + u(rng)) * 1e-3 * t, 10e-6),
        Eigen::Isometry3d::Identity(), "h - 1 = " + std::to_string(h - 1));
  }
}

TEST(LoopWireAnalytic, TangentAndGrazingContact) {
  // The segment x = R, z = z0 along y: distance |z0| at y = 0 (k ≥ R everywhere).
  const double R = 2e-3, r_l = 0.2e-3, r_w = 0.1e-3;
  const LoopDef loop{R, r_l};
  for (const double rel : {-1e-3, -1e-9, -1e-12, 0.0, 1e-12, 1e-9, 1e-3}) {
    const double z0 = (r_l + r_w) * (1 + rel);
    const WireDef w = SegmentWire({R, -3 * R, z0}, {R, 5 * R, z0}, r_w);
    const LoopWireModel model(loop, w);
    const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
    EXPECT_NEAR(c.clearance_m, z0 - r_l - r_w, 1e-15 * R) << rel;
    if (std::abs(rel) >= 1e-12) {
      EXPECT_EQ(c.contact, rel < 0) << rel;
    }
  }
  // An arc on a meridian of the loop's torus: every point at distance ρ from the circle.
  for (const double rho : {1e-3, 0.3, 0.999}) {
    WireDef w;
    w.radius_m = r_w;
    w.pieces.push_back(WirePieceDef::Arc({R, 0, 0}, {0, 1, 0}, {1, 0, 0}, rho * R, 1.5 * kPi));
    const LoopWireModel model(loop, w);
    const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
    EXPECT_NEAR(c.distance_m, rho * R, 1e-15 * R) << rho;
  }
}

TEST(LoopWireAnalytic, SegmentWhoseNearestPointIsAnEnd) {
  const double R = 1e-3;
  const LoopDef loop{R, 0.1 * R};
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    // Start at a point p, leave along a direction whose distance grows from p on: radially
    // outward from the circle's nearest point, tilted by < 60°.
    const double phi = kPi * u(rng), h = 0.01 + std::abs(u(rng));
    const double elev = 0.9 * kPi / 2 * u(rng);
    const Eigen::Vector3d radial(std::cos(phi), std::sin(phi), 0);
    const Eigen::Vector3d n = std::cos(elev) * radial + std::sin(elev) * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d p = R * radial + h * R * n;  // distance h R from the circle
    const WireDef w = SegmentWire(p, p + 5 * R * n, 10e-6);
    const LoopWireModel model(loop, w);
    const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
    EXPECT_NEAR(c.distance_m, h * R, 1e-15 * R);
    EXPECT_NEAR((c.p_WA - p).norm(), 0, 1e-15 * R);
    EXPECT_NEAR(c.s_m, 0, 1e-15 * R);
  }
}

TEST(LoopWireAnalytic, CoaxialAndCoplanarArcs) {
  const double R = 2e-3;
  const LoopDef loop{R, 0.1 * R};
  for (const double rho : {0.2, 0.999999, 1.0, 1.5}) {
    for (const double h : {0.0, 1e-9, 0.5}) {
      for (const double sweep : {1e-9, 1e-3, kPi, 2 * kPi - 1e-12, 2 * kPi}) {
        WireDef w;
        w.radius_m = 10e-6;
        w.pieces.push_back(WirePieceDef::Arc({0, 0, h * R}, {0, 0, 1}, {1, 0, 0}, rho * R, sweep));
        const LoopWireModel model(loop, w);
        const LoopWireClearance c = CalcLoopWireClearance(model, Eigen::Isometry3d::Identity());
        EXPECT_NEAR(c.distance_m, std::hypot(rho - 1, h) * R, 1e-15 * R)
            << rho << " " << h << " " << sweep;
        EXPECT_EQ(c.status, LoopWireStatus::kOk);
      }
    }
  }
}

TEST(LoopWireAnalytic, ArcSweepsNearZeroAndFullTurn) {
  std::mt19937_64 rng(31);
  const double R = 1e-3;
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    const double sweep = i % 2 ? std::pow(10.0, -12 + 11 * (u(rng) + 1) / 2)
                               : 2 * kPi - std::pow(10.0, -12 + 11 * (u(rng) + 1) / 2);
    const Eigen::Vector3d axis = testing::RandomRotation(rng) * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d uu = axis.unitOrthogonal();
    WireDef w;
    w.radius_m = 10e-6;
    w.pieces.push_back(WirePieceDef::Arc(Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1.5 * R, axis,
                                         uu, (0.2 + 2 * (u(rng) + 1)) * R, sweep));
    const LoopDef loop{R, 0.1 * R};
    ExpectAgreesWithReference(loop, w, Eigen::Isometry3d::Identity(),
                              "sweep " + std::to_string(sweep));
  }
}

TEST(LoopWireAnalytic, GentleTurnsOfRadiusUpTo3000R) {
  // Arcs of radius 10…3000 R passing within 1.5 R of the loop's centre: the whole-circle level
  // torus loses the small extrema near the loop there (once off by up to 0.57 R); the local
  // forms answer.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const double R = 1e-3;
  const LoopDef loop{R, 0.1 * R};
  for (int i = 0; i < 300; ++i) {
    const double rho = std::pow(10.0, 1 + 1.75 * (u(rng) + 1)) * R;
    const Eigen::Vector3d p0 = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1.5 * R;
    const Eigen::Vector3d axis = testing::RandomRotation(rng) * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d uu = axis.unitOrthogonal(), vv = axis.cross(uu);
    const double sweep = std::min(2 * kPi, 20 * R / rho * (1 + u(rng)) + 1e-3);
    const Eigen::Vector3d radial = std::cos(0.5 * sweep) * uu + std::sin(0.5 * sweep) * vv;
    WireDef w;
    w.radius_m = 10e-6;
    w.pieces.push_back(WirePieceDef::Arc(p0 - rho * radial, axis, uu, rho, sweep));
    ExpectAgreesWithReference(loop, w, Eigen::Isometry3d::Identity(),
                              "rho/R " + std::to_string(rho / R));
  }
}

TEST(LoopWireArc, LocalFormsAgreeWithTheWholeCircleFormOnSmallArcs) {
  // Both certificates on the same arcs (units of R): the local forms forced everywhere.
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d o = 2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Matrix3d rot = testing::RandomRotation(rng).toRotationMatrix();
    const double rho = 0.1 + 1.9 * (u(rng) + 1), sweep = kPi * (u(rng) + 1);
    const LoopWirePieceMin whole =
        CalcArcCircleMin(o, rot.col(0), rot.col(1), rho, rho * rho - 1, sweep, 1e300);
    const LoopWirePieceMin local =
        CalcArcCircleMin(o, rot.col(0), rot.col(1), rho, rho * rho - 1, sweep, 0);
    EXPECT_NEAR(std::sqrt(local.dist_sq), std::sqrt(whole.dist_sq), 1e-13) << i;
    EXPECT_TRUE(local.converged && whole.converged);
  }
}

TEST(LoopWireAnalytic, MetreLongStraightsAgainstAMillimetreLoop) {
  std::mt19937_64 rng(3);
  const double R = 1e-3;
  const WireDef w = MakeWireCourse(
      Eigen::Isometry3d::Identity(),
      {WireCourseStepDef::Straight(1.0), WireCourseStepDef::Turn(5 * R, kPi / 2, 0.3),
       WireCourseStepDef::Straight(1.0)},
      0.2e-3);
  RandomLoopWire s{LoopDef{R, 0.1 * R}, w};
  for (int k = 0; k < 12; ++k) {
    ExpectAgreesWithReference(s.loop, s.wire, testing::MakeThreadedPose(rng, s, R, kPi / 3),
                              "pose " + std::to_string(k));
  }
}

TEST(LoopWireAnalytic, FarPoses) {
  std::mt19937_64 rng(4);
  const RandomLoopWire s = testing::MakeRandomLoopWire(rng, 1e-3);
  for (const double far : {0.1, 10.0, 1e3}) {
    for (int k = 0; k < 5; ++k) {
      Eigen::Isometry3d X = testing::MakeWidePose(rng, s, 1e-3);
      X.translation() += far * (testing::RandomRotation(rng) * Eigen::Vector3d::UnitX());
      ExpectAgreesWithReference(s.loop, s.wire, X, "far " + std::to_string(far));
    }
  }
}

// The identity the arc's certificate rests on: the lifted level torus along an arc
// (arc_torus_sp.h) is −(d² − t²)(D² − t²), d and D the distances to the nearest and the
// farthest point of the unit core circle.
TEST(LoopWireArc, LevelTorusAlongTheArcIsMinusTheProductOfTheDistanceGaps) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d o = 2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Matrix3d rot = testing::RandomRotation(rng).toRotationMatrix();
    const double rho = 0.1 + 3 * (u(rng) + 1), t = 1.5 * (u(rng) + 1), s = kPi * u(rng);
    double size = 0;
    const CircleConic q =
        CalcLevelTorusAlongNeedle(o, rot.col(0), rot.col(1), rho, rho * rho - 1, t * t, &size);
    const Eigen::Vector3d x = o + rho * (std::cos(s) * rot.col(0) + std::sin(s) * rot.col(1));
    const double k = std::hypot(x.x(), x.y());
    const double d2 = (k - 1) * (k - 1) + x.z() * x.z(), D2 = (k + 1) * (k + 1) + x.z() * x.z();
    EXPECT_NEAR(q.Eval(std::cos(s), std::sin(s)), -(d2 - t * t) * (D2 - t * t), 1e-13 * size);
  }
}

// ---- Progress -------------------------------------------------------------------------------

TEST(LoopWireProgress, ArcLengthOffsetAndTangentAgreeWithDenseSampling) {
  std::mt19937_64 rng(8);
  for (int course = 0; course < 30; ++course) {
    const RandomLoopWire s = testing::MakeRandomLoopWire(rng, 2e-3);
    const LoopWireModel model(s.loop, s.wire);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d p = testing::MakeThreadedPose(rng, s, 2e-3, 0).translation();
      const WireProgress pr = CalcWireProgress(model, p);
      ASSERT_EQ(pr.status, LoopWireStatus::kOk);
      // Brute force: the course point at arc length σ for dense σ, every sampled local
      // minimum refined by golden-section search.
      const int n = 4000;
      const double h = model.length_m() / n;
      const auto dist = [&](double sig) {
        Eigen::Vector3d q, t;
        testing::CoursePointAt(s.wire, sig, &q, &t);
        return (q - p).norm();
      };
      std::vector<double> f(n + 1);
      for (int i = 0; i <= n; ++i) f[i] = dist(h * i);
      double best = 1e300;
      for (int i = 0; i <= n; ++i) {
        if ((i > 0 && f[i] > f[i - 1]) || (i < n && f[i] > f[i + 1])) continue;
        double a = h * std::max(0, i - 1), b = h * std::min(n, i + 1);
        const double g = (std::sqrt(5.0) - 1) / 2;
        for (int it = 0; it < 100 && b - a > 1e-16; ++it) {
          const double x1 = b - g * (b - a), x2 = a + g * (b - a);
          if (dist(x1) <= dist(x2)) {
            b = x2;
          } else {
            a = x1;
          }
        }
        best = std::min({best, f[i], dist(a), dist(b)});
      }
      EXPECT_NEAR(pr.distance_m, best, 1e-12 * 2e-3);
      Eigen::Vector3d q, t;
      testing::CoursePointAt(s.wire, pr.s_m, &q, &t);
      EXPECT_NEAR((q - pr.p_WA).norm(), 0, 1e-12);
      EXPECT_NEAR((t - pr.t_W).norm(), 0, 1e-9);
      EXPECT_NEAR((p - pr.p_WA).norm(), pr.distance_m, 1e-15);
    }
  }
}

TEST(LoopWireProgress, StraightAndTurnAnalytic) {
  const double R = 2e-3;
  const WireDef w = MakeWireCourse(
      Eigen::Isometry3d::Identity(),
      {WireCourseStepDef::Straight(10 * R), WireCourseStepDef::Turn(4 * R, kPi / 2, 0)}, 1e-4);
  const LoopWireModel model(LoopDef{R, 0.1 * R}, w);
  WireProgress pr = CalcWireProgress(model, {3 * R, 0.5 * R, -0.2 * R});
  EXPECT_NEAR(pr.s_m, 3 * R, 1e-15);
  EXPECT_NEAR(pr.distance_m, std::hypot(0.5, 0.2) * R, 1e-15);
  EXPECT_NEAR((pr.t_W - Eigen::Vector3d::UnitX()).norm(), 0, 1e-15);
  // In the turn, at 30° of it, 0.5 R outside and 0.1 R above the path.
  const Eigen::Vector3d centre(10 * R, 4 * R, 0);
  const double a = kPi / 6;
  const Eigen::Vector3d radial(std::sin(a), -std::cos(a), 0);
  pr = CalcWireProgress(model, centre + 4.5 * R * radial + Eigen::Vector3d(0, 0, 0.1 * R));
  EXPECT_NEAR(pr.s_m, 10 * R + 4 * R * a, 1e-14);
  EXPECT_NEAR(pr.distance_m, std::hypot(0.5, 0.1) * R, 1e-15);
  EXPECT_NEAR((pr.t_W - Eigen::Vector3d(std::cos(a), std::sin(a), 0)).norm(), 0, 1e-14);
  // Past the end: the end, at the full length.
  pr = CalcWireProgress(model, centre + Eigen::Vector3d(4 * R, 3 * R, 0));
  EXPECT_NEAR(pr.s_m, model.length_m(), 1e-15);
}

// ---- Hot path -------------------------------------------------------------------------------

TEST(LoopWireQuery, QueriesDoNotAllocate) {
  std::mt19937_64 rng(99);
  const RandomLoopWire s = testing::MakeRandomLoopWire(rng, 2e-3);
  const LoopWireModel model(s.loop, s.wire);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(501);
  for (int k = 0; k < 500; ++k) poses.push_back(testing::MakeThreadedPose(rng, s, 2e-3, kPi / 3));
  poses.push_back(Eigen::Isometry3d(Eigen::Matrix4d::Constant(std::nan(""))));
  volatile double sink = 0;
  ::microdex::testing::StartCountingAllocations();
  for (const Eigen::Isometry3d& X : poses) {
    sink = sink + CalcLoopWireClearance(model, X).clearance_m;
    sink = sink + CalcWireProgress(model, X.translation()).s_m;
  }
  EXPECT_EQ(::microdex::testing::StopCountingAllocations(), 0u);
}

}  // namespace
}  // namespace microdex::geometry
