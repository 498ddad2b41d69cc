#pragma once
// The loop-along-a-wire tests' and benchmark's independent reference and random scenes.
//
// The reference distance works straight from the Defs and the pose, in long double: each
// piece is sampled densely (spacing ≤ min(R, arc radius)/64, at least 64 samples), and every
// sampled local minimum of the distance to the loop's core circle is refined by golden-section
// search on the distance itself (not its square, so that a wire crossing the circle, where the
// distance is V-shaped, is located to rounding too).

#include <random>

#include "common/geometry/loop_wire.h"

namespace microdex::geometry::testing {

struct LoopWireReference {
  long double distance_m = 0;  // between the wire's axis and the loop's core circle
  int piece = -1;
  long double u = 0;  // the piece's parameter in [0, 1] (fraction of its length)
  Eigen::Vector3d p_WA = Eigen::Vector3d::Zero();
};

LoopWireReference CalcLoopWireReference(const LoopDef& loop, const WireDef& wire,
                                        const Eigen::Isometry3d& X_WL);

// A random course of 2–8 steps: straight runs of 0.3–5 R, turns of radius 0.3–5 R, angle
// 0.05–1.9π, in random planes; wire radius 0.02–0.3 R; from a random start pose within 5 R of
// the origin. The loop: R = radius_m, r_l 0.02–0.3 R.
struct RandomLoopWire {
  LoopDef loop;
  WireDef wire;
};
RandomLoopWire MakeRandomLoopWire(std::mt19937_64& rng, double radius_m);

// The loop threaded on the wire: its centre at the course point of a random arc length,
// moved by up to max_offset (⊥ to the tangent, random direction), its axis the tangent tilted
// by up to max_tilt_rad in a random direction.
Eigen::Isometry3d MakeThreadedPose(std::mt19937_64& rng, const RandomLoopWire& scene,
                                   double max_offset_m, double max_tilt_rad);
// Anywhere within `reach` of a random course point, any orientation.
Eigen::Isometry3d MakeWidePose(std::mt19937_64& rng, const RandomLoopWire& scene, double reach_m);

// The course point and unit tangent at arc length s (clamped to the course).
void CoursePointAt(const WireDef& wire, double s_m, Eigen::Vector3d* p_W, Eigen::Vector3d* t_W);

}  // namespace microdex::geometry::testing
