#include "tests/unit/geometry/loop_wire_reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry::testing {
namespace {

using Ld = long double;
using Vec = Eigen::Matrix<Ld, 3, 1>;
using Mat = Eigen::Matrix<Ld, 3, 3>;

struct LoopFrameLd {
  Mat R_LW;
  Vec p_WLo;
  Ld R = 1;
  Ld Dist(const Vec& p_W) const {
    const Vec p = R_LW * (p_W - p_WLo);
    const Ld k = std::sqrt(p.x() * p.x() + p.y() * p.y());
    return std::hypot(k - R, p.z());
  }
};

Vec ToLd(const Eigen::Vector3d& v) { return v.cast<Ld>(); }

// The piece's point at u ∈ [0, 1], in long double.
Vec PieceAt(const WirePieceDef& d, Ld u) {
  if (d.kind == WirePieceDef::Kind::kSegment)
    return ToLd(d.p_W0) + u * (ToLd(d.p_W1) - ToLd(d.p_W0));
  const Vec axis = ToLd(d.axis_W).normalized();
  Vec uu = ToLd(d.u_W);
  uu = (uu - uu.dot(axis) * axis).normalized();
  const Vec vv = axis.cross(uu);
  const Ld s = u * static_cast<Ld>(d.sweep_rad);
  return ToLd(d.p_WO) + static_cast<Ld>(d.radius_m) * (std::cos(s) * uu + std::sin(s) * vv);
}

}  // namespace

LoopWireReference CalcLoopWireReference(const LoopDef& loop, const WireDef& wire,
                                        const Eigen::Isometry3d& X_WL) {
  LoopFrameLd lf;
  lf.R_LW = X_WL.linear().cast<Ld>().transpose();
  lf.p_WLo = ToLd(X_WL.translation());
  lf.R = loop.radius_m;
  LoopWireReference best;
  best.distance_m = std::numeric_limits<Ld>::infinity();
  const Ld gr = (std::sqrt(5.0L) - 1) / 2;
  std::vector<Ld> f;
  for (std::size_t i = 0; i < wire.pieces.size(); ++i) {
    const WirePieceDef& d = wire.pieces[i];
    const double feature =
        d.kind == WirePieceDef::Kind::kArc ? std::min(loop.radius_m, d.radius_m) : loop.radius_m;
    const int n = std::max(64, static_cast<int>(std::ceil(64 * d.Length() / feature)));
    f.assign(static_cast<std::size_t>(n) + 1, 0);
    for (int j = 0; j <= n; ++j) f[j] = lf.Dist(PieceAt(d, static_cast<Ld>(j) / n));
    for (int j = 0; j <= n; ++j) {
      const bool left_ok = j == 0 || f[j] <= f[j - 1];
      const bool right_ok = j == n || f[j] <= f[j + 1];
      if (!(left_ok && right_ok)) continue;
      Ld a = static_cast<Ld>(std::max(0, j - 1)) / n, b = static_cast<Ld>(std::min(n, j + 1)) / n;
      Ld x1 = b - gr * (b - a), x2 = a + gr * (b - a);
      Ld f1 = lf.Dist(PieceAt(d, x1)), f2 = lf.Dist(PieceAt(d, x2));
      for (int it = 0; it < 200 && b - a > 1e-21L; ++it) {
        if (f1 <= f2) {
          b = x2;
          x2 = x1;
          f2 = f1;
          x1 = b - gr * (b - a);
          f1 = lf.Dist(PieceAt(d, x1));
        } else {
          a = x1;
          x1 = x2;
          f1 = f2;
          x2 = a + gr * (b - a);
          f2 = lf.Dist(PieceAt(d, x2));
        }
      }
      // The ends of the bracket and the sample itself stay candidates (a minimum at an end).
      const Ld cand_u[4] = {x1, x2, static_cast<Ld>(j) / n, a};
      for (const Ld u : cand_u) {
        const Vec p = PieceAt(d, u);
        const Ld dist = lf.Dist(p);
        if (dist < best.distance_m) {
          best.distance_m = dist;
          best.piece = static_cast<int>(i);
          best.u = u;
          best.p_WA = p.cast<double>();
        }
      }
    }
  }
  return best;
}

RandomLoopWire MakeRandomLoopWire(std::mt19937_64& rng, double R) {
  std::uniform_real_distribution<double> u01(0, 1);
  const auto uniform = [&](double a, double b) { return a + (b - a) * u01(rng); };
  RandomLoopWire s;
  s.loop.radius_m = R;
  s.loop.wire_radius_m = uniform(0.02, 0.3) * R;
  const int steps = 2 + static_cast<int>(u01(rng) * 7);
  std::vector<WireCourseStepDef> def;
  for (int i = 0; i < steps; ++i) {
    if (u01(rng) < 0.5) {
      def.push_back(WireCourseStepDef::Straight(uniform(0.3, 5) * R));
    } else {
      def.push_back(WireCourseStepDef::Turn(uniform(0.3, 5) * R,
                                            uniform(0.05, 1.9) * std::numbers::pi,
                                            uniform(0, 2 * std::numbers::pi)));
    }
  }
  Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();
  X_WS.linear() = RandomRotation(rng).toRotationMatrix();
  X_WS.translation() = Eigen::Vector3d(uniform(-5, 5), uniform(-5, 5), uniform(-5, 5)) * R;
  s.wire = MakeWireCourse(X_WS, def, uniform(0.02, 0.3) * R);
  return s;
}

void CoursePointAt(const WireDef& wire, double s_m, Eigen::Vector3d* p_W, Eigen::Vector3d* t_W) {
  double s0 = 0;
  for (std::size_t i = 0; i < wire.pieces.size(); ++i) {
    const WirePieceDef& d = wire.pieces[i];
    const double len = d.Length();
    if (s_m <= s0 + len || i + 1 == wire.pieces.size()) {
      const double u = std::clamp((s_m - s0) / len, 0.0, 1.0);
      if (d.kind == WirePieceDef::Kind::kSegment) {
        *p_W = d.p_W0 + u * (d.p_W1 - d.p_W0);
        *t_W = (d.p_W1 - d.p_W0).normalized();
      } else {
        const Eigen::Vector3d v = d.axis_W.cross(d.u_W);
        const double a = u * d.sweep_rad;
        *p_W = d.p_WO + d.radius_m * (std::cos(a) * d.u_W + std::sin(a) * v);
        *t_W = (std::cos(a) * v - std::sin(a) * d.u_W).normalized();
      }
      return;
    }
    s0 += len;
  }
}

Eigen::Isometry3d MakeThreadedPose(std::mt19937_64& rng, const RandomLoopWire& scene,
                                   double max_offset_m, double max_tilt_rad) {
  std::uniform_real_distribution<double> u01(0, 1);
  double length = 0;
  for (const WirePieceDef& d : scene.wire.pieces) length += d.Length();
  Eigen::Vector3d p, t;
  CoursePointAt(scene.wire, u01(rng) * length, &p, &t);
  // Two unit vectors ⊥ t.
  const Eigen::Vector3d a = t.unitOrthogonal(), b = t.cross(a);
  const double phi = 2 * std::numbers::pi * u01(rng);
  const Eigen::Vector3d off_dir = std::cos(phi) * a + std::sin(phi) * b;
  const double tilt = max_tilt_rad * u01(rng), psi = 2 * std::numbers::pi * u01(rng);
  const Eigen::Vector3d tilt_axis = std::cos(psi) * a + std::sin(psi) * b;
  const Eigen::Vector3d z = Eigen::AngleAxisd(tilt, tilt_axis) * t;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d x = z.unitOrthogonal();
  const Eigen::Matrix3d spin =
      Eigen::AngleAxisd(2 * std::numbers::pi * u01(rng), z).toRotationMatrix();
  X.linear().col(0) = spin * x;
  X.linear().col(1) = z.cross(spin * x);
  X.linear().col(2) = z;
  X.translation() = p + max_offset_m * u01(rng) * off_dir;
  return X;
}

Eigen::Isometry3d MakeWidePose(std::mt19937_64& rng, const RandomLoopWire& scene, double reach_m) {
  std::uniform_real_distribution<double> u(-1, 1);
  double length = 0;
  for (const WirePieceDef& d : scene.wire.pieces) length += d.Length();
  Eigen::Vector3d p, t;
  CoursePointAt(scene.wire, 0.5 * (u(rng) + 1) * length, &p, &t);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = RandomRotation(rng).toRotationMatrix();
  X.translation() = p + reach_m * Eigen::Vector3d(u(rng), u(rng), u(rng));
  return X;
}

}  // namespace microdex::geometry::testing
