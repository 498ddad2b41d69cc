#include "common/geometry/arc_torus_sp_lift.h"

#include <cmath>

namespace microdex::geometry {
namespace sp {
namespace {

// The lifted circle's geometry loses about eps/R̂ relative accuracy; below this radius, or
// when its centre and radius are inconsistent with S³, the robust path takes over.
constexpr double kMinLiftedRadius = 1e-9;
constexpr double kLiftedConsistencyTol = 1e-8;

}  // namespace

ScaledLiftedCircle LiftCircleScaled(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                    const Eigen::Vector3d& e2, const Eigen::Vector3d& n, double rho,
                                    double inv_rho) {
  // The needle circle is its plane n·x = n·o (n = e1 × e2) cut by its sphere |x − o|² = ρ².
  // Through P (4.2) each becomes a hyperplane of R⁴: n₁·X = h₁ with n₁ = (n, h₁), h₁ = n·o,
  // and n₂·X = h₂ with n₂ = (−2o, 1 − k), h₂ = −(1 + k), k = |o|² − ρ² (substitute
  // x = (l, m, p)/(1 − q), |x|² = (1 + q)/(1 − q)). Their intersection is the plane π of
  // (4.7); its point nearest the origin is the centre c (4.8) = a n₁ + b n₂, from the 2×2
  // Gram system. Here |n₁|² = 1 + h₁², n₁·n₂ = −h₁(1 + k), |n₂|² = 4|o|² + (1 − k)², so its
  // determinant is 4|o|² + (1 − k)² + 4h₁²ρ² (a sum of squares: no cancellation), a = 4h₁ρ²/det
  // and b = −(1 + k)/det. This replaces the triple cross products of (4.7) (no subtraction of
  // nearly equal lifted points) and needs one division (checked against the Gram–Schmidt form
  // and against lifted needle points in arc_torus_sp_test.cc).
  const double h1 = n.dot(o);
  const double o2 = o.squaredNorm(), rho2 = rho * rho;
  const double k = o2 - rho2;
  const double det = 4 * o2 + (1 - k) * (1 - k) + 4 * h1 * h1 * rho2;
  const double a = 4 * h1 * rho2, b = -(1 + k);
  // det · c = a n₁ + b n₂.
  const Eigen::Vector4d c_det(a * n.x() - 2 * b * o.x(), a * n.y() - 2 * b * o.y(),
                              a * n.z() - 2 * b * o.z(), a * h1 + b * (1 - k));
  // (4.9)–(4.10): the first axis through the lift (4.3) of the needle's s = 0 point,
  // X₀ = (2x₀, |x₀|² − 1)/N₀ with N₀ = |x₀|² + 1.
  const Eigen::Vector3d x0 = o + rho * e1;
  const double x0_sq = x0.squaredNorm();
  const double n0 = x0_sq + 1;
  const double inv = 1 / (n0 * det);
  ScaledLiftedCircle lc;
  lc.center = c_det * (n0 * inv);
  const Eigen::Vector4d lifted0(2 * x0.x(), 2 * x0.y(), 2 * x0.z(), x0_sq - 1);
  lc.ax = lifted0 * (det * inv) - lc.center;
  lc.radius_sq = lc.ax.squaredNorm();
  // (4.11)–(4.12): the second axis, the lifted tangent at s = 0, which also orients θ with s.
  // N₀ dP⁻¹(x₀)·ρe₂ = 2(N₀ρe₂ − 2(x₀·ρe₂)x₀, 2x₀·ρe₂)/N₀ has length 2ρ (P⁻¹ is conformal with
  // factor 2/N₀), and it is ⊥ a_x (a tangent of the circle at X₀): scaled to length R̂ it is a_y.
  const Eigen::Vector3d v = rho * e2;
  const double xv = x0.dot(v);
  const Eigen::Vector3d t3 = n0 * v - 2 * xv * x0;  // length N₀ρ together with t's last entry
  const Eigen::Vector4d t(t3.x(), t3.y(), t3.z(), 2 * xv);
  lc.ay = t * (std::sqrt(lc.radius_sq) * det * inv * inv_rho);
  return lc;
}

CircleConic CalcScaledCircleConic(double alpha, const ScaledLiftedCircle& lc) {
  const double a2 = alpha * alpha;
  const auto q = [a2](const Eigen::Vector4d& u, const Eigen::Vector4d& v) {
    return a2 * (u[0] * v[0] + u[1] * v[1]) - u[2] * v[2] - u[3] * v[3];
  };
  CircleConic k;
  k.a = q(lc.ax, lc.ax);
  k.b = 2 * q(lc.ax, lc.ay);
  k.c = q(lc.ay, lc.ay);
  k.d = 2 * q(lc.center, lc.ax);
  k.e = 2 * q(lc.center, lc.ay);
  k.f = q(lc.center, lc.center);
  return k;
}

void LiftLevelTorus(const NeedleInV& nv, double tube_t, double d2, LiftedConic* out) {
  LiftedConic& k = *out;
  // Appendix B (as CalcTorusLiftScale), then §4.2.3: lift the torus and the needle circle to
  // S³. The square roots of d2 and of t² run side by side.
  const double sd = std::sqrt(d2);  // 1/λ
  k.lambda = 1 / sd;
  k.alpha = tube_t * k.lambda;
  k.lc = LiftCircleScaled(k.lambda * nv.o, nv.e1, nv.e2, nv.e3, k.lambda * nv.rho, sd * nv.inv_rho);
  const ScaledLiftedCircle& lc = k.lc;
  k.radius = std::sqrt(lc.radius_sq);
  k.ok = lc.center.allFinite() && lc.ax.allFinite() && lc.ay.allFinite() &&
         k.radius > kMinLiftedRadius &&
         std::abs(lc.center.squaredNorm() + lc.radius_sq - 1) <= kLiftedConsistencyTol;
  if (!k.ok) return;
  // (4.15), (4.28): the conic on the lifted circle.
  k.conic = CalcScaledCircleConic(k.alpha, lc);
  k.phi_size = std::abs(k.conic.a) + std::abs(k.conic.b) + std::abs(k.conic.c) +
               std::abs(k.conic.d) + std::abs(k.conic.e) + std::abs(k.conic.f);
}

}  // namespace sp

LiftedCircle CalcLiftedCircle(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                              const Eigen::Vector3d& e2, double rho) {
  const sp::ScaledLiftedCircle scaled = sp::LiftCircleScaled(o, e1, e2, e1.cross(e2), rho, 1 / rho);
  LiftedCircle lc;
  lc.center = scaled.center;
  lc.radius = std::sqrt(scaled.radius_sq);
  lc.bx = scaled.ax * (1 / lc.radius);
  lc.by = scaled.ay * (1 / lc.radius);
  return lc;
}

CircleConic CalcCircleConic(double alpha, const LiftedCircle& lc) {
  // (4.15): G = α²(l² + m²) − (p² + q²) at c + x b_x + y b_y, with x = R̂ cos θ, y = R̂ sin θ.
  const double a2 = alpha * alpha;
  const auto q = [a2](const Eigen::Vector4d& u, const Eigen::Vector4d& v) {
    return a2 * (u[0] * v[0] + u[1] * v[1]) - u[2] * v[2] - u[3] * v[3];
  };
  const double rr = lc.radius;
  CircleConic k;
  k.a = q(lc.bx, lc.bx) * rr * rr;
  k.b = 2 * q(lc.bx, lc.by) * rr * rr;
  k.c = q(lc.by, lc.by) * rr * rr;
  k.d = 2 * q(lc.center, lc.bx) * rr;
  k.e = 2 * q(lc.center, lc.by) * rr;
  k.f = q(lc.center, lc.center);
  return k;
}

}  // namespace microdex::geometry
