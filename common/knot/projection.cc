#include "common/knot/projection.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "common/base/check.h"

namespace microdex::knot {
namespace {

// Relative tolerance of the genericity tests (times the polygon's extent).
constexpr double kGenericRelTol = 1e-7;

struct PassageAt {
  double t = 0.0;  // parameter along the edge
  int crossing = 0;
  bool over = false;
};

double Cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

}  // namespace

std::optional<GaussCode> ProjectPolygon(std::span<const Eigen::Vector3d> vertices,
                                        const Eigen::Vector3d& toward_viewer_W) {
  const int m = static_cast<int>(vertices.size());
  MICRODEX_CHECK(m >= 3);
  const Eigen::Vector3d d = toward_viewer_W.normalized();
  // e1 x e2 = d: a right-handed screen frame seen by the viewer.
  const Eigen::Vector3d e1 = d.unitOrthogonal();
  const Eigen::Vector3d e2 = d.cross(e1);
  std::vector<Eigen::Vector2d> q(m);
  std::vector<double> height(m);
  Eigen::AlignedBox2d box;
  for (int i = 0; i < m; ++i) {
    q[i] = {vertices[i].dot(e1), vertices[i].dot(e2)};
    height[i] = vertices[i].dot(d);
    box.extend(q[i]);
  }
  const double extent = std::max(box.sizes().maxCoeff(), 1e-300);
  const double tol = kGenericRelTol * extent;
  // Edge boxes for a quick reject.
  std::vector<Eigen::AlignedBox2d> edge_box(m);
  for (int i = 0; i < m; ++i) {
    edge_box[i] =
        Eigen::AlignedBox2d(q[i].cwiseMin(q[(i + 1) % m]) - Eigen::Vector2d::Constant(tol),
                            q[i].cwiseMax(q[(i + 1) % m]) + Eigen::Vector2d::Constant(tol));
  }
  std::vector<std::vector<PassageAt>> on_edge(m);
  GaussCode code;
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector2d a = q[i];
    const Eigen::Vector2d b = q[(i + 1) % m];
    const Eigen::Vector2d ab = b - a;
    const double len_ab = ab.norm();
    // Consecutive edges overlap only when folded back along the same line.
    {
      const Eigen::Vector2d bc = q[(i + 2) % m] - b;
      const double len_bc = bc.norm();
      if (len_ab < tol || len_bc < tol) return std::nullopt;
      if (std::abs(Cross2(ab, bc)) <= tol * (len_ab + len_bc) && ab.dot(bc) < 0) {
        return std::nullopt;
      }
    }
    for (int j = i + 2; j < m; ++j) {
      if (i == 0 && j == m - 1) continue;  // adjacent through vertex 0
      if (!edge_box[i].intersects(edge_box[j])) continue;
      const Eigen::Vector2d c = q[j];
      const Eigen::Vector2d dd = q[(j + 1) % m];
      const Eigen::Vector2d cd = dd - c;
      const double len_cd = cd.norm();
      // Signed distances of each endpoint from the other edge's line.
      const double o1 = Cross2(ab, c - a) / len_ab;
      const double o2 = Cross2(ab, dd - a) / len_ab;
      const double o3 = Cross2(cd, a - c) / len_cd;
      const double o4 = Cross2(cd, b - c) / len_cd;
      const bool near =
          std::abs(o1) <= tol || std::abs(o2) <= tol || std::abs(o3) <= tol || std::abs(o4) <= tol;
      if (near) {
        // An endpoint lies (nearly) on the other edge's line: not generic if it is also
        // within the other edge's extent.
        auto within = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& s0,
                          const Eigen::Vector2d& s) {
          const double u = (p - s0).dot(s) / s.squaredNorm();
          return u > -tol / s.norm() && u < 1.0 + tol / s.norm();
        };
        if ((std::abs(o1) <= tol && within(c, a, ab)) ||
            (std::abs(o2) <= tol && within(dd, a, ab)) ||
            (std::abs(o3) <= tol && within(a, c, cd)) ||
            (std::abs(o4) <= tol && within(b, c, cd))) {
          return std::nullopt;
        }
        continue;
      }
      if ((o1 > 0) == (o2 > 0) || (o3 > 0) == (o4 > 0)) continue;
      const double t_ab = o3 / (o3 - o4);
      const double t_cd = o1 / (o1 - o2);
      const double h_ab = height[i] + t_ab * (height[(i + 1) % m] - height[i]);
      const double h_cd = height[j] + t_cd * (height[(j + 1) % m] - height[j]);
      if (std::abs(h_ab - h_cd) <= tol) return std::nullopt;
      const bool ab_over = h_ab > h_cd;
      const Eigen::Vector2d& d_over = ab_over ? ab : cd;
      const Eigen::Vector2d& d_under = ab_over ? cd : ab;
      // Positive crossing: the over-strand turns counter-clockwise onto the under-strand.
      const int sign = Cross2(d_over, d_under) > 0 ? 1 : -1;
      const int id = code.num_crossings();
      code.sign.push_back(sign);
      on_edge[i].push_back({t_ab, id, ab_over});
      on_edge[j].push_back({t_cd, id, !ab_over});
    }
  }
  for (int i = 0; i < m; ++i) {
    auto& list = on_edge[i];
    std::sort(list.begin(), list.end(),
              [](const PassageAt& x, const PassageAt& y) { return x.t < y.t; });
    for (std::size_t k = 0; k < list.size(); ++k) {
      if (k > 0 && list[k].t - list[k - 1].t <= kGenericRelTol) return std::nullopt;
      code.passages.push_back({list[k].crossing, list[k].over});
    }
  }
  return code;
}

}  // namespace microdex::knot
