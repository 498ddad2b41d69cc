#pragma once
// The signed Gauss code of a closed polygon seen along a direction.

#include <Eigen/Core>
#include <optional>
#include <span>

#include "common/knot/diagram.h"

namespace microdex::knot {

// Projects the closed polygon `vertices` (the last vertex joins the first) on the plane
// normal to `toward_viewer_W` (unit; the viewer looks along -toward_viewer_W, "over" is the
// strand nearer the viewer) and returns its signed Gauss code, or nullopt if the direction
// is not generic for this polygon within a relative tolerance (a crossing near a vertex,
// overlapping or folded-back edges, two strands at nearly the same height at a crossing):
// the caller then tries another direction.
std::optional<GaussCode> ProjectPolygon(std::span<const Eigen::Vector3d> vertices,
                                        const Eigen::Vector3d& toward_viewer_W);

}  // namespace microdex::knot
