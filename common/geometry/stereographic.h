#pragma once
// Stereographic projection between the unit sphere S³ ⊂ R⁴ and R³ (thesis §4.2.1), and the
// normalisation of appendix B that makes a torus the image of the quadric (4.4).
//
// S³ points are (l, m, p, q) with l² + m² + p² + q² = 1; the projection pole is (0, 0, 0, 1),
// the image of ∞. Everything here is inline: it runs inside the 1 kHz haptic step.

#include <Eigen/Core>
#include <cmath>

namespace microdex::geometry {

// P⁻¹ (4.3): R³ → S³.
inline Eigen::Vector4d LiftToS3(const Eigen::Vector3d& x) {
  const double rho2 = x.squaredNorm();
  const double inv = 1.0 / (rho2 + 1.0);
  return Eigen::Vector4d(2 * x.x() * inv, 2 * x.y() * inv, 2 * x.z() * inv, (rho2 - 1.0) * inv);
}

// dP⁻¹(x)·v: the tangent that P⁻¹ maps the R³ velocity v at x to (derivative of (4.3)).
inline Eigen::Vector4d LiftTangentToS3(const Eigen::Vector3d& x, const Eigen::Vector3d& v) {
  const double rho2 = x.squaredNorm();
  const double inv = 1.0 / (rho2 + 1.0);
  const double xv = x.dot(v);
  const Eigen::Vector3d t = 2 * inv * v - 4 * inv * inv * xv * x;
  return Eigen::Vector4d(t.x(), t.y(), t.z(), 4 * inv * inv * xv);
}

// P (4.2): S³ \ {pole} → R³.
inline Eigen::Vector3d ProjectFromS3(const Eigen::Vector4d& X) {
  const double inv = 1.0 / (1.0 - X[3]);
  return Eigen::Vector3d(X[0] * inv, X[1] * inv, X[2] * inv);
}

// Appendix B: a torus with core radius R and tube radius r (0 < r < R), scaled by
// λ = 1/√(R² − r²) so that R̃² − r̃² = 1 (B.2), is the projection of
// α²(l² + m²) − (p² + q²) = 0 (4.4) with α = r̃ (B.3), equivalently α² = β²/(1 − β²) with
// β = r/R (B.5).
struct TorusLiftScale {
  double lambda = 1;  // [1/m] multiply R³ lengths by this to reach the normalised torus
  double alpha = 0;   // α of (4.4), dimensionless
};

inline TorusLiftScale CalcTorusLiftScale(double core_radius, double tube_radius) {
  // (R − r)(R + r) instead of R² − r²: no cancellation when r → R.
  const double d2 = (core_radius - tube_radius) * (core_radius + tube_radius);
  TorusLiftScale s;
  s.lambda = 1.0 / std::sqrt(d2);
  s.alpha = tube_radius * s.lambda;
  return s;
}

// G of (4.4) at a point of S³: positive inside the lifted tube, zero on it, negative outside.
inline double EvalLiftedTorus(double alpha, const Eigen::Vector4d& X) {
  return alpha * alpha * (X[0] * X[0] + X[1] * X[1]) - (X[2] * X[2] + X[3] * X[3]);
}

}  // namespace microdex::geometry
