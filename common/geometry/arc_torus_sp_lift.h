#pragma once
// SP stage 2, lift (thesis §4.2.3, appendix B): the torus normalised and lifted to the quadric
// G = α²(l² + m²) − (p² + q²) of S³, the needle circle lifted to a circle of S³, and the
// conic φ(θ) of G on it (4.15), (4.28). Internal to the SP clearance (arc_torus_sp.cc);
// exposed for its stage tests.

#include <Eigen/Core>

#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/arc_torus_sp_clip.h"

namespace microdex::geometry::sp {

// The lifted circle with its axes scaled by its radius, a_x = R̂ b_x and a_y = R̂ b_y: all that
// the conic (4.15) and the map back (4.13) need, formed with three divisions and one square
// root (unit axes cost three more of each, on the critical path of every pass).
struct ScaledLiftedCircle {
  Eigen::Vector4d center, ax, ay;
  double radius_sq = 0;  // R̂²
};

// The needle circle x(s) = o + ρ(cos s e1 + sin s e2) (n = e1 × e2, inv_rho = 1/ρ), in the
// normalised torus frame, lifted to S³ with its axes scaled by its radius.
ScaledLiftedCircle LiftCircleScaled(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                    const Eigen::Vector3d& e2, const Eigen::Vector3d& n, double rho,
                                    double inv_rho);

// (4.15): G = α²(l² + m²) − (p² + q²) at c + cos θ a_x + sin θ a_y.
CircleConic CalcScaledCircleConic(double alpha, const ScaledLiftedCircle& lc);

// The lifted needle circle and the conic of the torus of tube radius t on it (appendix B,
// §4.2.3, (4.15)).
struct LiftedConic {
  bool ok = false;  // false: lifted circle too ill-conditioned (README_sp.md, "Fallbacks")
  double lambda = 1, alpha = 0;
  ScaledLiftedCircle lc;
  double radius = 0;  // R̂
  CircleConic conic;
  double phi_size = 0;  // |A| + … + |F|: the scale of φ's values and of their rounding
};

// Lifts the torus of core radius R and tube radius t (d2 = R² − t², formed by the caller as
// accurately as its inputs allow) and the needle circle; out->ok false when the lifted circle
// is too ill-conditioned to use.
void LiftLevelTorus(const NeedleInV& nv, double tube_t, double d2, LiftedConic* out);

}  // namespace microdex::geometry::sp
