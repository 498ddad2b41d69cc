#pragma once
// Isotopy reduction of a closed polygon (triangle moves): a vertex is deleted when the
// triangle it spans with its two neighbours meets no other edge, which moves the curve by an
// ambient isotopy and keeps its knot type. Repeated until no vertex can go, this shrinks a
// thread of hundreds of nodes to a handful of vertices whose projections have few crossings.

#include <Eigen/Core>
#include <span>
#include <vector>

namespace microdex::knot {

// Returns the indices (increasing) of the vertices of `closed` that remain; at least 3.
// The tests are conservative: a triangle that comes within a relative tolerance of an edge
// is kept.
std::vector<int> ReducePolygon(std::span<const Eigen::Vector3d> closed);

// Whether the segment [p, q] meets the triangle (a, b, c) or comes within `tol_m` of it
// (conservative: may answer true for a near miss, never false for a hit).
bool SegmentMayMeetTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, double tol_m);

}  // namespace microdex::knot
