// The SP query never allocates (it runs in the 1 kHz haptic step): every operator new of this
// binary, and malloc outside sanitizer builds, is counted around the calls.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <numbers>

#include "common/geometry/arc_torus_sp.h"
#include "tests/support/alloc_counter.h"

namespace microdex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;

struct Query {
  ArcDef arc;
  TorusSegmentDef torus;
};

Query MakeQuery(double rho, double sweep, double omega, const Eigen::Vector3d& center_V,
                const Eigen::Matrix3d& R_VN) {
  Query q;
  q.torus.core_radius_m = 5e-3;
  q.torus.tube_radius_m = 0.5e-3;
  q.torus.segment_angle_rad = omega;
  q.arc.radius_m = rho;
  q.arc.sweep_rad = sweep;
  q.arc.X_WN.linear() = R_VN;
  q.arc.X_WN.translation() = center_V;
  return q;
}

TEST(ArcTorusSpAllocation, NoAllocationPerQuery) {
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(0.1, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  const Query near = MakeQuery(5.1e-3, 2.0, 3.0, Eigen::Vector3d(0.1e-3, 0.2e-3, 0.1e-3), tilt);
  const Query on_core = MakeQuery(5e-3, 2.0, 2 * kPi, Eigen::Vector3d::Zero(),
                                  Eigen::Matrix3d::Identity());  // robust path
  const Query deep = MakeQuery(
      2.5e-3, kPi, 2 * kPi, Eigen::Vector3d::Zero(),
      Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());  // exact path
  Query invalid = near;
  invalid.arc.radius_m = -1;
  SpDiagnostics diag;
  double sink = CalcArcTorusClearanceSP(near.arc, near.torus).clearance_m;  // warm-up
  ::microdex::testing::StartCountingAllocations();
  for (int i = 0; i < 100; ++i) {
    sink += CalcArcTorusClearanceSP(near.arc, near.torus).clearance_m;
    sink += CalcArcTorusClearanceSP(on_core.arc, on_core.torus).clearance_m;
    sink += CalcArcTorusClearanceSP(deep.arc, deep.torus, {}, &diag).clearance_m;
    sink += CalcArcTorusClearanceSP(invalid.arc, invalid.torus).s_rad;
  }
  EXPECT_EQ(::microdex::testing::StopCountingAllocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace microdex::geometry
