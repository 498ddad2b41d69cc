#pragma once
// Closing an open thread into a knot: each free end is continued by a straight ray out of
// the thread's bounding ball, radially out to a sphere twice as large, and the two points on
// that sphere are joined along a great circle. Everything outside the bounding ball is then
// unknotted and unlinked from the thread, so the knot type depends only on the two rays.
//
// The ray leaves an end along the thread's own direction when that direction is clear of
// the rest of the thread (an angular clearance of at least 45 degrees); otherwise along the
// widest empty cone seen from the end (the candidate direction maximising the angle to the
// nearest node, nodes taken as balls of the thread's radius), biased towards the end's
// direction. So an end lying inside a knot or pointing back into it does not thread its
// closure through the knot.

#include <Eigen/Core>
#include <span>
#include <vector>

namespace microdex::knot {

// The direction in which the closure leaves the end node (`at_last` picks the last node,
// otherwise the first). `thread_diameter_m` > 0.
Eigen::Vector3d ChooseExitDirection(std::span<const Eigen::Vector3d> nodes, bool at_last,
                                    double thread_diameter_m);

// The closed polygon: the thread's nodes in order, then the closure's vertices (the last
// vertex joins the first). `nodes` has at least two nodes, consecutive ones distinct.
std::vector<Eigen::Vector3d> CloseThread(std::span<const Eigen::Vector3d> nodes,
                                         double thread_diameter_m);

}  // namespace microdex::knot
