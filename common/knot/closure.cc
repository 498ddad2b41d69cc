#include "common/knot/closure.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/base/check.h"

namespace microdex::knot {
namespace {

constexpr double kPi = std::numbers::pi;
// The end's own direction is kept when its angular clearance reaches this.
constexpr double kTangentClearance_rad = kPi / 4;
// Clearance beyond this counts as fully open when comparing candidate directions.
constexpr double kOpenClearance_rad = kPi / 2;
// Weight of the alignment with the end's direction in the score of a candidate.
constexpr double kTangentBias_rad = 0.25;
// Quasi-uniform candidate directions.
constexpr int kNumCandidates = 48;
// Largest angle between consecutive vertices of the closing great-circle arc.
constexpr double kArcStep_rad = kPi / 9;

// acos with an absolute error below 7e-5 rad (Abramowitz & Stegun 4.4.45): the clearance
// only ranks directions, so this accuracy is ample and avoids libm's cost.
double FastAcos(double x) {
  const double a = std::abs(x);
  const double r =
      std::sqrt(1.0 - a) * (1.5707288 + a * (-0.2121144 + a * (0.0742610 - 0.0187293 * a)));
  return x >= 0.0 ? r : kPi - r;
}

// The nodes as seen from an end: unit directions and angular radii (balls of radius r).
struct View {
  std::vector<Eigen::Vector3d> dir;
  std::vector<double> radius_rad;
};

View ViewFrom(std::span<const Eigen::Vector3d> nodes, int skip, double r) {
  View view;
  view.dir.reserve(nodes.size());
  view.radius_rad.reserve(nodes.size());
  const Eigen::Vector3d& p = nodes[skip];
  for (int i = 0; i < static_cast<int>(nodes.size()); ++i) {
    if (i == skip) continue;
    const Eigen::Vector3d x = nodes[i] - p;
    const double dist = x.norm();
    if (dist <= 0.0) continue;
    view.dir.push_back(x / dist);
    view.radius_rad.push_back(std::asin(std::min(1.0, r / dist)));
  }
  return view;
}

// Smallest angle between the ray direction u and the nodes of the view.
double AngularClearance(const View& view, const Eigen::Vector3d& u) {
  double clearance = kPi;
  for (std::size_t i = 0; i < view.dir.size(); ++i) {
    const double cos_angle = std::clamp(u.dot(view.dir[i]), -1.0, 1.0);
    clearance = std::min(clearance, FastAcos(cos_angle) - view.radius_rad[i]);
  }
  return clearance;
}

Eigen::Vector3d FibonacciDirection(int i, int n) {
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  const double z = 1.0 - 2.0 * (i + 0.5) / n;
  const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {rho * std::cos(golden * i), rho * std::sin(golden * i), z};
}

}  // namespace

Eigen::Vector3d ChooseExitDirection(std::span<const Eigen::Vector3d> nodes, bool at_last,
                                    double thread_diameter_m) {
  const int n = static_cast<int>(nodes.size());
  MICRODEX_CHECK(n >= 2 && thread_diameter_m > 0);
  const int end = at_last ? n - 1 : 0;
  const int step = at_last ? -1 : 1;
  const Eigen::Vector3d& p = nodes[end];
  // The end's direction over about two diameters of thread.
  int back = end + step;
  double arc = (nodes[back] - p).norm();
  while (arc < 2.0 * thread_diameter_m && back + step >= 0 && back + step < n &&
         std::abs(back - end) < 8) {
    arc += (nodes[back + step] - nodes[back]).norm();
    back += step;
  }
  Eigen::Vector3d tangent = p - nodes[back];
  // A thread that comes back onto its end node: use the last link (never zero).
  if (tangent.norm() <= 0.0) tangent = p - nodes[end + step];
  MICRODEX_CHECK(tangent.norm() > 0);
  tangent.normalize();
  const View view = ViewFrom(nodes, end, 0.5 * thread_diameter_m);
  if (AngularClearance(view, tangent) >= kTangentClearance_rad) return tangent;

  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& x : nodes) centroid += x;
  centroid /= n;
  Eigen::Vector3d best = tangent;
  double best_score = -1e300;
  auto consider = [&](const Eigen::Vector3d& u) {
    const double clearance = std::min(AngularClearance(view, u), kOpenClearance_rad);
    const double score = clearance + kTangentBias_rad * u.dot(tangent);
    if (score > best_score) {
      best_score = score;
      best = u;
    }
  };
  consider(tangent);
  const Eigen::Vector3d outward = p - centroid;
  if (outward.norm() > 0) consider(outward.normalized());
  // Candidates in a frame made of the end's direction and the direction away from the
  // centroid, so that the choice turns with the thread (rigid motions change nothing).
  Eigen::Vector3d side = outward - outward.dot(tangent) * tangent;
  side = side.norm() > 1e-9 * outward.norm() && side.norm() > 0 ? side.normalized()
                                                                : tangent.unitOrthogonal();
  Eigen::Matrix3d frame;
  frame << tangent, side, tangent.cross(side);
  for (int i = 0; i < kNumCandidates; ++i) {
    consider(frame * FibonacciDirection(i, kNumCandidates));
  }
  return best;
}

std::vector<Eigen::Vector3d> CloseThread(std::span<const Eigen::Vector3d> nodes,
                                         double thread_diameter_m) {
  const int n = static_cast<int>(nodes.size());
  MICRODEX_CHECK(n >= 2);
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  for (const auto& x : nodes) center += x;
  center /= n;
  double radius = 0.0;
  for (const auto& x : nodes) radius = std::max(radius, (x - center).norm());
  // The ball every node lies in, and the sphere the closure runs on.
  const double r_inner = 1.1 * radius + thread_diameter_m;
  const double r_outer = 2.0 * r_inner;

  auto exit_point = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& u) {
    // p + s u on the inner sphere, s > 0 (p is inside it).
    const Eigen::Vector3d w = p - center;
    const double b = u.dot(w);
    const double c = w.squaredNorm() - r_inner * r_inner;
    const double s = -b + std::sqrt(std::max(0.0, b * b - c));
    return Eigen::Vector3d(p + s * u);
  };
  const Eigen::Vector3d exit_last =
      exit_point(nodes[n - 1], ChooseExitDirection(nodes, true, thread_diameter_m));
  const Eigen::Vector3d exit_first =
      exit_point(nodes[0], ChooseExitDirection(nodes, false, thread_diameter_m));
  const Eigen::Vector3d dir_last = (exit_last - center).normalized();
  const Eigen::Vector3d dir_first = (exit_first - center).normalized();

  std::vector<Eigen::Vector3d> closed(nodes.begin(), nodes.end());
  closed.push_back(exit_last);
  // Great-circle arc from dir_last to dir_first on the outer sphere.
  const double angle = std::acos(std::clamp(dir_last.dot(dir_first), -1.0, 1.0));
  Eigen::Vector3d axis = dir_last.cross(dir_first);
  if (axis.norm() < 1e-9) axis = dir_last.unitOrthogonal();
  axis.normalize();
  const int steps = std::max(1, static_cast<int>(std::ceil(angle / kArcStep_rad)));
  for (int k = 0; k <= steps; ++k) {
    if (k == steps && angle < 1e-9) break;  // both ends leave the same way: one far point
    const Eigen::Vector3d dir = Eigen::AngleAxisd(angle * k / steps, axis) * dir_last;
    closed.push_back(center + r_outer * dir);
  }
  closed.push_back(exit_first);
  return closed;
}

}  // namespace microdex::knot
