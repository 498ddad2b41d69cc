#pragma once
// Baseline of the loop-along-a-wire clearance (loop_wire.h): the wire's axis sampled at N
// evenly spaced points per piece, the clearance taken at the sample nearest to the loop's core
// circle. Never below the exact clearance; its error falls like the square of the spacing
// where the nearest point is interior (a smooth minimum between two samples).

#include "common/geometry/loop_wire.h"

namespace microdex::geometry {

// N ≥ 2 points per piece (fewer is treated as 2), both ends included, over the pieces that
// the model's bounding spheres do not exclude. No allocation, no exception (a pose that is not
// finite: kInvalidPose).
LoopWireClearance CalcLoopWireClearanceSampled(const LoopWireModel& model,
                                               const Eigen::Isometry3d& X_WL, int samples);

}  // namespace microdex::geometry
