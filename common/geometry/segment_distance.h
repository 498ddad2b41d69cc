#pragma once
// Closest points between two segments (link–link contact, link–capsule contact).

#include <Eigen/Core>

namespace microdex::geometry {

struct SegmentClosest {
  double s = 0.0;  // parameter on the first segment, p = a0 + s (a1 - a0), s in [0, 1]
  double t = 0.0;  // parameter on the second segment
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
  double distance_m = 0.0;
};

// Exact closest points of segments [a0, a1] and [b0, b1] (Ericson, Real-Time Collision
// Detection §5.1.9), robust to degenerate (zero-length) and parallel segments.
SegmentClosest ClosestSegmentSegment(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                     const Eigen::Vector3d& b0, const Eigen::Vector3d& b1);

// Closest point parameter of point p on segment [a0, a1], in [0, 1].
double ClosestSegmentPointParam(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                const Eigen::Vector3d& p);

}  // namespace microdex::geometry
