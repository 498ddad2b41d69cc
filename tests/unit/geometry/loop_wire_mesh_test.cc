// Peer check of the loop-along-a-wire clearance (loop_wire.h) against FCL on triangle meshes
// (loop_wire_mesh.h), and the sampled baseline's bounds (loop_wire_sampled.h).
#include "common/geometry/loop_wire_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "common/geometry/loop_wire_sampled.h"
#include "tests/unit/geometry/loop_wire_reference.h"

namespace microdex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;

double Sagitta(double radius, int n) { return radius * (1 - std::cos(kPi / n)); }

double MaxTurnRadius_m(const LoopWireModel& model) {
  double max_turn = 0;
  for (const LoopWireModel::Piece& p : model.pieces()) max_turn = std::max(max_turn, p.radius_m);
  return max_turn;
}

// How far the meshes' surfaces can lie inside their solids (vertices on the surfaces, facets
// cut the convex directions): the sagittas of the loop's circle and section, of the wire's
// section, and of the chords that replace its arcs.
double MeshInside_m(const LoopWireModel& model, const LoopWireMeshResolution& res) {
  return Sagitta(model.loop().radius_m + model.loop().wire_radius_m, res.n_major) +
         Sagitta(model.loop().wire_radius_m, res.n_minor) +
         Sagitta(model.wire_radius_m(), res.n_around) +
         Sagitta(MaxTurnRadius_m(model), res.n_major);
}

// And outside them: on the concave side of each tube around a curved axis (the loop's hole,
// the inside of the wire's turns) the facets bulge out by the sagitta of the axis's chords.
double MeshOutside_m(const LoopWireModel& model, const LoopWireMeshResolution& res) {
  return Sagitta(model.loop().radius_m, res.n_major) + Sagitta(MaxTurnRadius_m(model), res.n_major);
}

TEST(LoopWireMesh, ContactFlagAndDistanceAgreeWithFclAwayFromGrazing) {
  std::mt19937_64 rng(2024);
  LoopWireMeshResolution res;
  res.n_major = 256;
  res.n_minor = 32;
  res.n_around = 32;
  int compared = 0, contacts = 0, distances = 0;
  for (int course = 0; course < 12; ++course) {
    const testing::RandomLoopWire s = testing::MakeRandomLoopWire(rng, 2e-3);
    const LoopWireModel model(s.loop, s.wire);
    const LoopWireMeshModel mesh(model, res);
    const double inside = MeshInside_m(model, res) + 1e-9;
    const double outside = MeshOutside_m(model, res) + 1e-9;
    const double margin = std::max(inside, outside);
    for (int k = 0; k < 40; ++k) {
      const Eigen::Isometry3d X_WL = testing::MakeThreadedPose(rng, s, 2e-3, kPi / 3);
      const LoopWireClearance c = CalcLoopWireClearance(model, X_WL);
      const LoopWireClearance m = mesh.Calc(X_WL);
      // Surfaces that cross (not one tube wholly inside the other) and are not grazing.
      const bool surfaces_cross =
          c.clearance_m < -margin &&
          c.distance_m > std::abs(s.loop.wire_radius_m - s.wire.radius_m) + margin;
      if (c.clearance_m > margin) {
        ++compared;
        EXPECT_FALSE(m.contact) << course << " " << k << " clearance " << c.clearance_m;
        // Within the sagittas, except where the nearest wire point is an end of the course:
        // the analytic wire is a union of balls (a round cap), the mesh tube is open there.
        const bool at_course_end =
            c.s_m < 1e-9 * model.length_m() || c.s_m > (1 - 1e-9) * model.length_m();
        if (!at_course_end) {
          EXPECT_GE(m.clearance_m, c.clearance_m - outside);
          EXPECT_LE(m.clearance_m, c.clearance_m + inside);
          ++distances;
        }
      } else if (surfaces_cross) {
        ++compared;
        ++contacts;
        EXPECT_TRUE(m.contact) << course << " " << k << " clearance " << c.clearance_m;
      }
    }
  }
  EXPECT_GT(contacts, 20);
  EXPECT_GT(distances, 20);
  EXPECT_GT(compared, 300);
}

TEST(LoopWireSampled, NeverBelowTheExactAndConvergesQuadratically) {
  std::mt19937_64 rng(11);
  double worst_coarse = 0, worst_fine = 0;
  for (int course = 0; course < 20; ++course) {
    const testing::RandomLoopWire s = testing::MakeRandomLoopWire(rng, 2e-3);
    const LoopWireModel model(s.loop, s.wire);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Isometry3d X_WL = testing::MakeThreadedPose(rng, s, 2e-3, kPi / 3);
      const LoopWireClearance c = CalcLoopWireClearance(model, X_WL);
      const LoopWireClearance a = CalcLoopWireClearanceSampled(model, X_WL, 200);
      const LoopWireClearance b = CalcLoopWireClearanceSampled(model, X_WL, 3200);
      EXPECT_GE(a.distance_m, c.distance_m - 1e-15);
      EXPECT_GE(b.distance_m, c.distance_m - 1e-15);
      worst_coarse = std::max(worst_coarse, a.distance_m - c.distance_m);
      worst_fine = std::max(worst_fine, b.distance_m - c.distance_m);
    }
  }
  // 16× the samples: the worst error divided by more than 16 (quadratic where the nearest
  // point is smooth, linear where the wire crosses the circle: the worst is in between).
  EXPECT_GT(worst_coarse, 0);
  EXPECT_LT(worst_fine, worst_coarse / 16);
}

}  // namespace
}  // namespace microdex::geometry
