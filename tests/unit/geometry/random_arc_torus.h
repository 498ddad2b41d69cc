#pragma once
// Random needle–vessel configurations for the geometry tests: valid inputs covering the
// whole parameter space (wide) and the training situation (needle close to the core circle).

#include <random>

#include "common/geometry/arc_torus.h"

namespace microdex::geometry::testing {

Eigen::Quaterniond RandomRotation(std::mt19937_64& rng);

struct RandomArcTorus {
  ArcDef arc;
  TorusSegmentDef torus;
};

// Wide: R = 1, r/R log-uniform in [1e-4, 0.99], needle radius log-uniform in
// [1e-2, 1e2]·R, centre within 3(R + ρ) of the vessel, random orientations, sweep and
// segment angle uniform in (0, 2π] with a share of exactly 2π.
RandomArcTorus MakeWideArcTorus(std::mt19937_64& rng);

// Training-like: R = 5 mm, r ∈ [0.05, 0.3]·R, needle radius ≈ R, the needle placed on the
// core circle and then moved by up to ~r and turned by up to ~r/R rad.
RandomArcTorus MakeNearCoreArcTorus(std::mt19937_64& rng);

// Applies X (rigid) to both frames, and scales every length by `scale`.
RandomArcTorus Transformed(const RandomArcTorus& c, const Eigen::Isometry3d& X, double scale);

}  // namespace microdex::geometry::testing
