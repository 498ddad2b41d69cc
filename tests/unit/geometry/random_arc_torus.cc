#include "tests/unit/geometry/random_arc_torus.h"

#include <cmath>
#include <numbers>

namespace microdex::geometry::testing {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

double Uniform(std::mt19937_64& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

double LogUniform(std::mt19937_64& rng, double a, double b) {
  return std::exp(Uniform(rng, std::log(a), std::log(b)));
}

// Angle in (0, 2π], exactly 2π one time in five.
double AngleUpToTwoPi(std::mt19937_64& rng) {
  if (Uniform(rng, 0, 1) < 0.2) return kTwoPi;
  return kTwoPi - Uniform(rng, 0, kTwoPi) * (1 - 1e-12);
}

}  // namespace

Eigen::Quaterniond RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q;
}

RandomArcTorus MakeWideArcTorus(std::mt19937_64& rng) {
  RandomArcTorus c;
  c.torus.core_radius_m = 1;
  c.torus.tube_radius_m = LogUniform(rng, 1e-4, 0.99);
  c.torus.segment_angle_rad = AngleUpToTwoPi(rng);
  c.torus.X_WV = Eigen::Isometry3d::Identity();
  c.torus.X_WV.linear() = RandomRotation(rng).toRotationMatrix();
  c.torus.X_WV.translation() = Eigen::Vector3d(Uniform(rng, -2, 2), Uniform(rng, -2, 2), 0);
  c.arc.radius_m = LogUniform(rng, 1e-2, 1e2);
  c.arc.sweep_rad = AngleUpToTwoPi(rng);
  c.arc.X_WN = Eigen::Isometry3d::Identity();
  c.arc.X_WN.linear() = RandomRotation(rng).toRotationMatrix();
  const double reach = 3 * (1 + c.arc.radius_m);
  c.arc.X_WN.translation() =
      c.torus.X_WV.translation() + Eigen::Vector3d(Uniform(rng, -reach, reach),
                                                   Uniform(rng, -reach, reach),
                                                   Uniform(rng, -reach, reach));
  return c;
}

RandomArcTorus MakeNearCoreArcTorus(std::mt19937_64& rng) {
  RandomArcTorus c;
  const double R = 5e-3;
  c.torus.core_radius_m = R;
  c.torus.tube_radius_m = Uniform(rng, 0.05, 0.3) * R;
  c.torus.segment_angle_rad = Uniform(rng, 0, 1) < 0.5 ? kTwoPi : Uniform(rng, 0.5, kTwoPi);
  c.torus.X_WV = Eigen::Isometry3d::Identity();
  c.torus.X_WV.linear() = RandomRotation(rng).toRotationMatrix();
  c.torus.X_WV.translation() =
      Eigen::Vector3d(Uniform(rng, -0.1, 0.1), Uniform(rng, -0.1, 0.1), Uniform(rng, -0.1, 0.1));
  const double r = c.torus.tube_radius_m;
  c.arc.radius_m = R * (1 + Uniform(rng, -0.2, 0.2) * r / R);
  c.arc.sweep_rad = Uniform(rng, 0.3, 1.2) * std::numbers::pi;
  // On the core circle, started at a random azimuth, then disturbed.
  const double start = Uniform(rng, -0.5, c.torus.segment_angle_rad);
  Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
  X_VN.linear() = Eigen::AngleAxisd(start, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const double tilt = Uniform(rng, 0, 1.5) * r / R;
  X_VN.linear() =
      Eigen::AngleAxisd(tilt, RandomRotation(rng) * Eigen::Vector3d::UnitX()) * X_VN.linear();
  X_VN.translation() =
      Eigen::Vector3d(Uniform(rng, -1, 1), Uniform(rng, -1, 1), Uniform(rng, -1, 1)) * 1.2 * r;
  c.arc.X_WN = c.torus.X_WV * X_VN;
  return c;
}

RandomArcTorus Transformed(const RandomArcTorus& c, const Eigen::Isometry3d& X, double scale) {
  RandomArcTorus out = c;
  out.arc.radius_m *= scale;
  out.torus.core_radius_m *= scale;
  out.torus.tube_radius_m *= scale;
  out.arc.X_WN.translation() *= scale;
  out.torus.X_WV.translation() *= scale;
  out.arc.X_WN = X * out.arc.X_WN;
  out.torus.X_WV = X * out.torus.X_WV;
  return out;
}

}  // namespace microdex::geometry::testing
