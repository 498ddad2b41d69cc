#include "common/grasp/grasp_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace microdex::grasp {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Clips [s_in, s_out] to the slab lo <= p + s d <= hi of one axis.
bool ClipSlab(double p, double d, double lo, double hi, double& s_in, double& s_out) {
  if (std::abs(d) < 1e-300) return p >= lo && p <= hi;
  double a = (lo - p) / d, b = (hi - p) / d;
  if (a > b) std::swap(a, b);
  s_in = std::max(s_in, a);
  s_out = std::min(s_out, b);
  return s_in <= s_out;
}

// Clips [s_in, s_out] to the disc |xy(p + s d)| <= r (the infinite cylinder about z).
bool ClipDisc(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double r, double& s_in,
              double& s_out) {
  const double a = d.x() * d.x() + d.y() * d.y();
  const double b = p.x() * d.x() + p.y() * d.y();
  const double c = p.x() * p.x() + p.y() * p.y() - r * r;
  if (a < 1e-300) return c <= 0.0;
  const double disc = b * b - a * c;
  if (disc < 0.0) return false;
  const double root = std::sqrt(disc);
  s_in = std::max(s_in, (-b - root) / a);
  s_out = std::min(s_out, (-b + root) / a);
  return s_in <= s_out;
}

}  // namespace

ShapeGeometry MakeShapeGeometry(const ShapeDef& def) {
  ShapeGeometry g;
  g.kind = def.kind;
  switch (def.kind) {
    case ShapeKind::kBox:
      g.half_extents_m = 0.5 * def.box_size_m;
      g.bounding_radius_m = g.half_extents_m.norm();
      break;
    case ShapeKind::kCylinder:
      g.radius_m = def.radius_m;
      g.half_length_m = 0.5 * def.length_m;
      g.bounding_radius_m = std::hypot(g.radius_m, g.half_length_m);
      break;
    case ShapeKind::kSphere:
      g.radius_m = def.radius_m;
      g.bounding_radius_m = def.radius_m;
      break;
  }
  return g;
}

MassProperties CalcMassProperties(const ShapeDef& def, double density_kg_per_m3) {
  MassProperties mp;
  const double pi = std::numbers::pi;
  switch (def.kind) {
    case ShapeKind::kBox: {
      const Eigen::Vector3d s = def.box_size_m;
      mp.mass_kg = density_kg_per_m3 * s.prod();
      const double k = mp.mass_kg / 12.0;
      mp.inertia_kg_m2 =
          Eigen::Vector3d(k * (s.y() * s.y() + s.z() * s.z()), k * (s.x() * s.x() + s.z() * s.z()),
                          k * (s.x() * s.x() + s.y() * s.y()));
      break;
    }
    case ShapeKind::kCylinder: {
      const double r = def.radius_m, l = def.length_m;
      mp.mass_kg = density_kg_per_m3 * pi * r * r * l;
      const double across = mp.mass_kg * (3.0 * r * r + l * l) / 12.0;
      mp.inertia_kg_m2 = Eigen::Vector3d(across, across, 0.5 * mp.mass_kg * r * r);
      break;
    }
    case ShapeKind::kSphere: {
      const double r = def.radius_m;
      mp.mass_kg = density_kg_per_m3 * 4.0 / 3.0 * pi * r * r * r;
      mp.inertia_kg_m2.setConstant(0.4 * mp.mass_kg * r * r);
      break;
    }
  }
  return mp;
}

int CalcSupportPoints(const ShapeGeometry& shape, const Eigen::Vector3d& d_O,
                      std::array<Eigen::Vector3d, kMaxSupportPoints>& points_O) {
  switch (shape.kind) {
    case ShapeKind::kBox: {
      const Eigen::Vector3d& h = shape.half_extents_m;
      for (int k = 0; k < 8; ++k) {
        points_O[k] = Eigen::Vector3d((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(),
                                      (k & 4) ? h.z() : -h.z());
      }
      return 8;
    }
    case ShapeKind::kSphere:
      points_O[0] = shape.radius_m * d_O;
      return 1;
    case ShapeKind::kCylinder: {
      // Rim directions: u, the projection of d_O on the cap plane (x when d_O is along the
      // axis), and v = z x u.
      const double rho = std::hypot(d_O.x(), d_O.y());
      const Eigen::Vector3d u = rho > 1e-9 ? Eigen::Vector3d(d_O.x() / rho, d_O.y() / rho, 0.0)
                                           : Eigen::Vector3d::UnitX();
      const Eigen::Vector3d v(-u.y(), u.x(), 0.0);
      const double r = shape.radius_m;
      for (int cap = 0; cap < 2; ++cap) {
        const Eigen::Vector3d c(0.0, 0.0, cap == 0 ? -shape.half_length_m : shape.half_length_m);
        points_O[4 * cap + 0] = c + r * u;
        points_O[4 * cap + 1] = c + r * v;
        points_O[4 * cap + 2] = c - r * v;
        points_O[4 * cap + 3] = c - r * u;
      }
      return 8;
    }
  }
  return 0;
}

int CalcSupportEdges(const ShapeGeometry& shape, SupportEdges& edges) {
  switch (shape.kind) {
    case ShapeKind::kBox: {
      int n = 0;
      for (int k = 0; k < 8; ++k) {
        for (int bit = 1; bit < 8; bit <<= 1) {
          if ((k & bit) == 0) edges[n++] = {k, k | bit};
        }
      }
      return n;
    }
    case ShapeKind::kCylinder:
      for (int k = 0; k < 4; ++k) edges[k] = {k, k + 4};
      return 4;
    case ShapeKind::kSphere:
      return 0;
  }
  return 0;
}

bool CalcLineInterval(const ShapeGeometry& shape, const Eigen::Vector3d& p_O,
                      const Eigen::Vector3d& d_O, double& s_in, double& s_out) {
  s_in = -kInf;
  s_out = kInf;
  switch (shape.kind) {
    case ShapeKind::kBox:
      for (int i = 0; i < 3; ++i) {
        const double h = shape.half_extents_m[i];
        if (!ClipSlab(p_O[i], d_O[i], -h, h, s_in, s_out)) return false;
      }
      return true;
    case ShapeKind::kSphere: {
      const double b = p_O.dot(d_O);
      const double c = p_O.squaredNorm() - shape.radius_m * shape.radius_m;
      const double disc = b * b - c;
      if (disc < 0.0) return false;
      const double root = std::sqrt(disc);
      s_in = -b - root;
      s_out = -b + root;
      return true;
    }
    case ShapeKind::kCylinder:
      if (!ClipSlab(p_O.z(), d_O.z(), -shape.half_length_m, shape.half_length_m, s_in, s_out)) {
        return false;
      }
      return ClipDisc(p_O, d_O, shape.radius_m, s_in, s_out);
  }
  return false;
}

}  // namespace microdex::grasp
