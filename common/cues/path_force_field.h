#pragma once
// Haptic guidance cues along the ideal path (thesis §2.1, Fig. 2.1): a convergent field pulls
// the tool towards the path, a divergent field pushes it away (training in unstable dynamics,
// after Burdet et al., which the thesis proposes for micromanipulation). The path here is a
// circle (the needle tail's ideal path around the vessel axis), so the field is the spring
//   f_T_W = -k_signed (p_WT − q_W),  q_W the nearest point of the path circle to p_WT,
// k_signed = +k (convergent) or −k (divergent), saturated at max_force_N.

#include <Eigen/Geometry>

namespace microdex::cues {

struct PathCircle {
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();  // circle in the xy-plane of C
  double radius_m = 5e-3;
};

struct PathSegment {
  Eigen::Vector3d a_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d b_W = Eigen::Vector3d::UnitX();
};

// The ideal path of a task: a circle or a segment.
struct IdealPath {
  bool is_segment = false;
  PathCircle circle;
  PathSegment segment;
};

// Nearest point of the segment to p_W (the end point beyond either end).
Eigen::Vector3d CalcNearestOnSegment(const PathSegment& segment, const Eigen::Vector3d& p_W);

// Nearest point of the circle to p_W; false (and q_W untouched) on the axis, where every
// circle point is nearest.
bool CalcNearestOnCircle(const PathCircle& circle, const Eigen::Vector3d& p_W,
                         Eigen::Vector3d* q_W);

// The field's spring towards (away from) the path point q_W nearest the tool, saturated: for a
// path of another shape (the loop's wire course), whose nearest point its module finds.
Eigen::Vector3d CalcPointFieldForce(const Eigen::Vector3d& p_WT, const Eigen::Vector3d& q_W,
                                    double signed_stiffness_N_per_m, double max_force_N);

// The spring force of the field; zero on the circle's axis. signed_stiffness_N_per_m > 0
// converges, < 0 diverges.
Eigen::Vector3d CalcPathFieldForce(const PathCircle& circle, const Eigen::Vector3d& p_WT,
                                   double signed_stiffness_N_per_m, double max_force_N);
// The divergent field of Fig. 2.1b (after Burdet et al.): unstable across the intended
// direction only. The push is k times the component of (p_WT − q_W) normal to the path's
// tangent at q_W, so that at a segment's ends the field does not push along the movement;
// saturated at max_force_N. stiffness_N_per_m >= 0.
Eigen::Vector3d CalcDivergentFieldForce(const IdealPath& path, const Eigen::Vector3d& p_WT,
                                        double stiffness_N_per_m, double max_force_N);

// The same towards (away from) either kind of path.
Eigen::Vector3d CalcPathFieldForce(const IdealPath& path, const Eigen::Vector3d& p_WT,
                                   double signed_stiffness_N_per_m, double max_force_N);

}  // namespace microdex::cues
