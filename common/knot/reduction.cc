#include "common/knot/reduction.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

#include "common/base/check.h"
#include "common/geometry/segment_distance.h"

namespace microdex::knot {
namespace {

// Tolerance of the triangle tests relative to the polygon's extent.
constexpr double kRelTol = 1e-9;
// Below this many vertices every edge is tested (no grid).
constexpr int kBruteForceBelow = 96;
// Grid resolution cap per axis; the largest cell span registered per edge before the edge
// goes to the list of long edges; a query visiting more cells than there are edges (and
// more than kMinCellsPerQuery) tests every edge instead.
constexpr int kMaxCellsPerAxis = 48;
constexpr int kMaxCellsPerEdge = 27;
constexpr long kMinCellsPerQuery = 64;

double Cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double PointSegmentDistance2(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                             const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double SegmentSegmentDistance2(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                               const Eigen::Vector2d& c, const Eigen::Vector2d& d) {
  const double o1 = Cross2(b - a, c - a);
  const double o2 = Cross2(b - a, d - a);
  const double o3 = Cross2(d - c, a - c);
  const double o4 = Cross2(d - c, b - c);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) {
    return 0.0;
  }
  return std::min({PointSegmentDistance2(a, c, d), PointSegmentDistance2(b, c, d),
                   PointSegmentDistance2(c, a, b), PointSegmentDistance2(d, a, b)});
}

class Reducer {
 public:
  explicit Reducer(std::span<const Eigen::Vector3d> pts)
      : pts_(pts),
        n_(static_cast<int>(pts.size())),
        next_(n_),
        prev_(n_),
        alive_(n_, true),
        stamp_(n_, 0),
        alive_count_(n_) {
    Eigen::AlignedBox3d box;
    for (int i = 0; i < n_; ++i) {
      next_[i] = (i + 1) % n_;
      prev_[i] = (i + n_ - 1) % n_;
      box.extend(pts_[i]);
    }
    tol_ = kRelTol * std::max(box.sizes().maxCoeff(), 1e-300);
  }

  std::vector<int> Run() {
    int head = 0;
    bool changed = true;
    while (changed && alive_count_ > 3) {
      changed = false;
      use_grid_ = alive_count_ >= kBruteForceBelow;
      if (use_grid_) BuildGrid(head);
      const int total = alive_count_;
      int v = head;
      for (int step = 0; step < total && alive_count_ > 3; ++step) {
        const int after = next_[v];
        if (TryDelete(v)) changed = true;
        v = after;
      }
      head = v;
    }
    std::vector<int> kept;
    for (int i = 0; i < n_; ++i) {
      if (alive_[i]) kept.push_back(i);
    }
    return kept;
  }

 private:
  Eigen::AlignedBox3d EdgeBox(int s) const {
    Eigen::AlignedBox3d box(pts_[s]);
    box.extend(pts_[next_[s]]);
    return box;
  }

  std::array<int, 6> CellRange(const Eigen::AlignedBox3d& box) const {
    std::array<int, 6> r{};
    for (int k = 0; k < 3; ++k) {
      r[k] = std::clamp(static_cast<int>(std::floor((box.min()[k] - tol_ - origin_[k]) / cell_)), 0,
                        dims_[k] - 1);
      r[3 + k] =
          std::clamp(static_cast<int>(std::floor((box.max()[k] + tol_ - origin_[k]) / cell_)), 0,
                     dims_[k] - 1);
    }
    return r;
  }

  static long CellCount(const std::array<int, 6>& r) {
    return static_cast<long>(r[3] - r[0] + 1) * (r[4] - r[1] + 1) * (r[5] - r[2] + 1);
  }

  void BuildGrid(int head) {
    Eigen::AlignedBox3d box;
    int v = head;
    std::vector<double> lengths;
    lengths.reserve(alive_count_);
    for (int k = 0; k < alive_count_; ++k) {
      box.extend(pts_[v]);
      lengths.push_back((pts_[next_[v]] - pts_[v]).norm());
      v = next_[v];
    }
    std::nth_element(lengths.begin(), lengths.begin() + static_cast<long>(lengths.size() / 2),
                     lengths.end());
    const double median = lengths[lengths.size() / 2];
    const double extent = box.sizes().maxCoeff();
    cell_ = std::max({1.5 * median, extent / kMaxCellsPerAxis, 1e-300});
    origin_ = box.min();
    for (int k = 0; k < 3; ++k) {
      dims_[k] = std::clamp(static_cast<int>(box.sizes()[k] / cell_) + 1, 1, kMaxCellsPerAxis + 1);
    }
    head_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2], -1);
    pool_.clear();
    long_edges_.clear();
    in_long_list_.assign(n_, false);
    v = head;
    for (int k = 0; k < alive_count_; ++k) {
      Register(v);
      v = next_[v];
    }
  }

  void Register(int s) {
    const auto r = CellRange(EdgeBox(s));
    if (CellCount(r) > kMaxCellsPerEdge) {
      // Once listed, an edge starting at s stays listed: the list holds start vertices.
      if (!in_long_list_[s]) {
        in_long_list_[s] = true;
        long_edges_.push_back(s);
      }
      return;
    }
    for (int z = r[2]; z <= r[5]; ++z) {
      for (int y = r[1]; y <= r[4]; ++y) {
        for (int x = r[0]; x <= r[3]; ++x) {
          int& h = head_[(static_cast<std::size_t>(z) * dims_[1] + y) * dims_[0] + x];
          pool_.push_back({s, h});
          h = static_cast<int>(pool_.size()) - 1;
        }
      }
    }
  }

  // Whether edge s (from s to next_[s]) blocks deleting v with neighbours a, b.
  bool Blocks(int s, int a, int v, int b) const {
    if (!alive_[s] || s == a || s == v || s == b || next_[s] == a) return false;
    return SegmentMayMeetTriangle(pts_[s], pts_[next_[s]], pts_[a], pts_[v], pts_[b], tol_);
  }

  bool TryDelete(int v) {
    const int a = prev_[v];
    const int b = next_[v];
    const Eigen::Vector3d& pa = pts_[a];
    const Eigen::Vector3d& pv = pts_[v];
    const Eigen::Vector3d& pb = pts_[b];
    const Eigen::Vector3d av = pv - pa;
    const Eigen::Vector3d vb = pb - pv;
    // v on the straight edge a-b: deleting it sweeps nothing.
    const bool straight = av.cross(vb).norm() <= kRelTol * av.norm() * vb.norm() && av.dot(vb) > 0;
    if (!straight && Blocked(a, v, b)) return false;
    next_[a] = b;
    prev_[b] = a;
    alive_[v] = false;
    --alive_count_;
    if (use_grid_) Register(a);
    return true;
  }

  bool Blocked(int a, int v, int b) {
    Eigen::AlignedBox3d box(pts_[a]);
    box.extend(pts_[v]);
    box.extend(pts_[b]);
    const auto r = use_grid_ ? CellRange(box) : std::array<int, 6>{};
    if (!use_grid_ || CellCount(r) > std::max<long>(kMinCellsPerQuery, alive_count_)) {
      int s = b;
      for (int k = 0; k < alive_count_; ++k) {
        if (Blocks(s, a, v, b)) return true;
        s = next_[s];
      }
      return false;
    }
    ++current_stamp_;
    for (int s : long_edges_) {
      if (stamp_[s] == current_stamp_) continue;
      stamp_[s] = current_stamp_;
      if (Blocks(s, a, v, b)) return true;
    }
    for (int z = r[2]; z <= r[5]; ++z) {
      for (int y = r[1]; y <= r[4]; ++y) {
        for (int x = r[0]; x <= r[3]; ++x) {
          for (int e = head_[(static_cast<std::size_t>(z) * dims_[1] + y) * dims_[0] + x]; e >= 0;
               e = pool_[e].next) {
            const int s = pool_[e].edge;
            if (stamp_[s] == current_stamp_) continue;
            stamp_[s] = current_stamp_;
            if (Blocks(s, a, v, b)) return true;
          }
        }
      }
    }
    return false;
  }

  struct Entry {
    int edge;
    int next;
  };

  std::span<const Eigen::Vector3d> pts_;
  int n_;
  std::vector<int> next_;
  std::vector<int> prev_;
  std::vector<bool> alive_;
  std::vector<int> stamp_;
  int current_stamp_ = 0;
  int alive_count_;
  double tol_ = 0.0;
  bool use_grid_ = false;
  double cell_ = 1.0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<int> head_;
  std::vector<Entry> pool_;
  std::vector<int> long_edges_;
  std::vector<bool> in_long_list_;
};

}  // namespace

bool SegmentMayMeetTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, double tol_m) {
  // Quick reject by boxes.
  for (int k = 0; k < 3; ++k) {
    const double lo = std::min({a[k], b[k], c[k]}) - tol_m;
    const double hi = std::max({a[k], b[k], c[k]}) + tol_m;
    if (std::max(p[k], q[k]) < lo || std::min(p[k], q[k]) > hi) return false;
  }
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d n = ab.cross(ac);
  const double nn = n.norm();
  if (nn <= kRelTol * ab.norm() * ac.norm() || nn == 0.0) {
    // Degenerate triangle: it is the union of its edges.
    return geometry::ClosestSegmentSegment(p, q, a, b).distance_m <= tol_m ||
           geometry::ClosestSegmentSegment(p, q, b, c).distance_m <= tol_m ||
           geometry::ClosestSegmentSegment(p, q, a, c).distance_m <= tol_m;
  }
  const Eigen::Vector3d nhat = n / nn;
  const double dp = nhat.dot(p - a);
  const double dq = nhat.dot(q - a);
  if ((dp > tol_m && dq > tol_m) || (dp < -tol_m && dq < -tol_m)) return false;
  // The part of [p, q] within tol of the plane: t in [t0, t1].
  double t0 = 0.0;
  double t1 = 1.0;
  const double slope = dq - dp;
  if (std::abs(slope) > 0.0) {
    const double ta = (-tol_m - dp) / slope;
    const double tb = (tol_m - dp) / slope;
    t0 = std::max(0.0, std::min(ta, tb));
    t1 = std::min(1.0, std::max(ta, tb));
    if (t0 > t1) return false;
  }
  // In-plane test of that part against the triangle.
  const Eigen::Vector3d u = ab / ab.norm();
  const Eigen::Vector3d w = nhat.cross(u);
  auto to2 = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector2d((x - a).dot(u), (x - a).dot(w));
  };
  const Eigen::Vector2d s0 = to2(p + t0 * (q - p));
  const Eigen::Vector2d s1 = to2(p + t1 * (q - p));
  const Eigen::Vector2d ta2(0.0, 0.0);
  const Eigen::Vector2d tb2 = to2(b);
  const Eigen::Vector2d tc2 = to2(c);
  // Inside (with margin): signed distances to the three edge lines (counter-clockwise).
  auto inside = [&](const Eigen::Vector2d& x) {
    const std::array<std::pair<Eigen::Vector2d, Eigen::Vector2d>, 3> edges{
        {{ta2, tb2}, {tb2, tc2}, {tc2, ta2}}};
    for (const auto& [e0, e1] : edges) {
      const Eigen::Vector2d e = e1 - e0;
      if (Cross2(e, x - e0) / e.norm() < -tol_m) return false;
    }
    return true;
  };
  if (inside(s0) || inside(s1)) return true;
  return SegmentSegmentDistance2(s0, s1, ta2, tb2) <= tol_m ||
         SegmentSegmentDistance2(s0, s1, tb2, tc2) <= tol_m ||
         SegmentSegmentDistance2(s0, s1, tc2, ta2) <= tol_m;
}

std::vector<int> ReducePolygon(std::span<const Eigen::Vector3d> closed) {
  MICRODEX_CHECK(closed.size() >= 3);
  return Reducer(closed).Run();
}

}  // namespace microdex::knot
