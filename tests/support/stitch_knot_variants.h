#pragma once
// Seeded random variants of the knots tied around a stitch, for the stitch-knot tests and the
// `microdex-bench knot --stitch-report` confusion matrix: tightness, stitch width and depth,
// tail length and directions, the knot's axis, mirror images, which strand is the post, then a
// rigid motion that keeps the tissue plane (rotation about z, translation in xy) and uniform
// noise on every coordinate.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/knot/stitch_knot.h"
#include "common/knot/stitch_knot_shapes.h"

namespace microdex::knot::variants {

struct StitchVariant {
  StitchKnotShapeDef def;
  std::vector<Eigen::Vector3d> thread;  // moved and noisy
};

// The generated classes, in the order of the confusion matrix's rows.
inline constexpr std::array<StitchKnotType, 6> kStitchClasses = {
    StitchKnotType::kNone,     StitchKnotType::kSquare, StitchKnotType::kGranny,
    StitchKnotType::kSurgeons, StitchKnotType::kSlip,   StitchKnotType::kHalfHitch};

// `count` variants of `kind` drawn from `seed`, with uniform noise of +-noise_diameters
// thread diameters on every coordinate and nodes `node_spacing_diameters` apart. Parameter
// draws that MakeStitchKnot rejects (tails aimed through the knot) are drawn again.
std::vector<StitchVariant> RandomStitchVariants(StitchKnotType kind, int count, std::uint64_t seed,
                                                double noise_diameters,
                                                double node_spacing_diameters = 1.0);

// Rows: generated class (kStitchClasses order); columns: recognised class (StitchKnotType
// order, kUnknown last).
using ConfusionMatrix = std::array<std::array<int, 7>, 6>;

// One line per row, the class words as headers.
std::string FormatConfusion(const ConfusionMatrix& m);

}  // namespace microdex::knot::variants
