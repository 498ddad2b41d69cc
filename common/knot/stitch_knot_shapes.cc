// Parametric stitch knots: stitch, legs, twisted pair along an axis, tails.
#include "common/knot/stitch_knot_shapes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/base/check.h"
#include "common/geometry/segment_distance.h"

namespace microdex::knot {
namespace {

constexpr double kPi = std::numbers::pi;
using Curve = std::vector<Eigen::Vector3d>;

struct Throw {
  int hand = 1;
  int turns = 1;
};

void AppendBezier(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                  const Eigen::Vector3d& p3, int samples, Curve& out) {
  for (int k = 1; k <= samples; ++k) {
    const double t = static_cast<double>(k) / samples;
    const double s = 1.0 - t;
    out.push_back(s * s * s * p0 + 3 * s * s * t * p1 + 3 * s * t * t * p2 + t * t * t * p3);
  }
}

Curve ResampleOpen(const Curve& open, double spacing) {
  const int segments = std::max(1, static_cast<int>(std::round(PolylineLength(open) / spacing)));
  return ResampleByArcLength(open, segments);
}

Eigen::Vector3d Direction(double azimuth, double elevation) {
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
          std::sin(elevation)};
}

}  // namespace

void StitchKnotShapeDef::Validate() const {
  auto finite_positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  switch (kind) {
    case StitchKnotType::kNone:
    case StitchKnotType::kSquare:
    case StitchKnotType::kGranny:
    case StitchKnotType::kSurgeons:
    case StitchKnotType::kSlip:
    case StitchKnotType::kHalfHitch:
      break;
    default:
      throw std::invalid_argument("StitchKnotShapeDef.kind: unknown is not a shape");
  }
  if (!finite_positive(thread_diameter_m)) {
    throw std::invalid_argument("StitchKnotShapeDef.thread_diameter_m: expected > 0");
  }
  if (!std::isfinite(node_spacing_m) || node_spacing_m < 0.0 ||
      node_spacing_m > 2.0 * thread_diameter_m) {
    throw std::invalid_argument(
        "StitchKnotShapeDef.node_spacing_m: expected 0 (one diameter) up to two diameters");
  }
  if (!std::isfinite(stitch_width_m) || stitch_width_m < 8.0 * thread_diameter_m) {
    throw std::invalid_argument(
        "StitchKnotShapeDef.stitch_width_m: expected at least 8 thread diameters");
  }
  if (!std::isfinite(stitch_depth_m) || stitch_depth_m < thread_diameter_m) {
    throw std::invalid_argument(
        "StitchKnotShapeDef.stitch_depth_m: expected at least one thread diameter");
  }
  if (!(tightness >= 0.0 && tightness <= 1.0)) {
    throw std::invalid_argument("StitchKnotShapeDef.tightness: expected in [0, 1]");
  }
  if (!std::isfinite(tail_length_m) || tail_length_m < 2.0 * thread_diameter_m) {
    throw std::invalid_argument(
        "StitchKnotShapeDef.tail_length_m: expected at least two thread diameters");
  }
  for (double el : {tail_first_elevation_rad, tail_last_elevation_rad}) {
    if (!(el >= 0.0 && el < kPi / 2)) {
      throw std::invalid_argument(
          "StitchKnotShapeDef.tail_*_elevation_rad: expected in [0, pi/2) (tails above the "
          "tissue)");
    }
  }
  if (!std::isfinite(tail_first_azimuth_rad) || !std::isfinite(tail_last_azimuth_rad)) {
    throw std::invalid_argument("StitchKnotShapeDef.tail_*_azimuth_rad: expected finite");
  }
  if (!(axis_tilt_rad >= 0.0 && axis_tilt_rad <= 1.2) || !std::isfinite(axis_azimuth_rad)) {
    throw std::invalid_argument(
        "StitchKnotShapeDef.axis_tilt_rad: expected in [0, 1.2] and a finite azimuth");
  }
  if (!(base_height_diameters >= 1.0 && base_height_diameters <= 100.0)) {
    throw std::invalid_argument("StitchKnotShapeDef.base_height_diameters: expected in [1, 100]");
  }
  if (post_strand != 1 && post_strand != 2) {
    throw std::invalid_argument("StitchKnotShapeDef.post_strand: expected 1 or 2");
  }
}

std::vector<Eigen::Vector3d> MakeStitchKnot(const StitchKnotShapeDef& def) {
  def.Validate();
  const double d = def.thread_diameter_m;
  const double loose = 1.0 - def.tightness;
  const bool hitch = def.kind == StitchKnotType::kSlip || def.kind == StitchKnotType::kHalfHitch;
  std::vector<Throw> throws;
  switch (def.kind) {
    case StitchKnotType::kSquare:
      throws = {{1, 1}, {-1, 1}};
      break;
    case StitchKnotType::kGranny:
      throws = {{1, 1}, {1, 1}};
      break;
    case StitchKnotType::kSurgeons:
      throws = {{1, 2}, {-1, 1}};
      break;
    case StitchKnotType::kSlip:
      throws = {{1, 1}, {def.slip_same_sense ? 1 : -1, 1}};
      break;
    case StitchKnotType::kHalfHitch:
      throws = {{1, 1}};
      break;
    default:
      break;
  }
  // Radii about the axis and pitch per full turn. A symmetric pair at radius r, sampled one
  // diameter apart, keeps its chords more than d apart from r = 0.68 d and a pitch of 2.8 d
  // (half a turn later the other strand is p / 2 away along the axis); a strand wound
  // around a straight post needs r >= 1.2 d.
  const double r_pair = d * (0.68 + 0.6 * loose);
  const double pitch_pair = d * (2.8 + 3.0 * loose);
  const double r_wound = d * (1.2 + 0.6 * loose);
  const double pitch_wound = d * (2.2 + 2.5 * loose);
  const double gap = d * (2.5 + 5.5 * loose);
  const double entry = 1.5 * d;
  const double exit = 1.0 * d;
  double ra = r_pair;
  double rb = r_pair;
  if (hitch) {
    ra = def.post_strand == 1 ? 0.0 : r_wound;
    rb = def.post_strand == 2 ? 0.0 : r_wound;
  }
  const double pitch = hitch ? pitch_wound : pitch_pair;

  // Axis frame: a along the axis, u towards +x (the side of the last puncture), v = a x u.
  const double tilt = def.axis_tilt_rad;
  const Eigen::Vector3d a(std::sin(tilt) * std::cos(def.axis_azimuth_rad),
                          std::sin(tilt) * std::sin(def.axis_azimuth_rad), std::cos(tilt));
  Eigen::Vector3d u = Eigen::Vector3d::UnitX() - a.x() * a;
  u = u.norm() > 1e-6 ? Eigen::Vector3d(u.normalized()) : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d v = a.cross(u);
  const Eigen::Vector3d base(0.0, 0.0, std::max(ra, rb) + def.base_height_diameters * d);

  // Twist angle along the axis: segments of (length, change of angle).
  std::vector<std::pair<double, double>> segments = {{entry, 0.0}};
  for (std::size_t i = 0; i < throws.size(); ++i) {
    segments.emplace_back(throws[i].turns * pitch, 2.0 * kPi * throws[i].hand * throws[i].turns);
    if (i + 1 < throws.size()) segments.emplace_back(gap, 0.0);
  }
  segments.emplace_back(exit, 0.0);
  Curve knot_a;
  Curve knot_b;
  double tau = 0.0;
  double phi = 0.0;
  auto radial = [&](double angle) {
    return Eigen::Vector3d(std::cos(angle) * u + std::sin(angle) * v);
  };
  auto emit = [&](double t, double angle) {
    knot_a.push_back(base + t * a - ra * radial(angle));
    knot_b.push_back(base + t * a + rb * radial(angle));
  };
  emit(0.0, 0.0);
  const double step = d / 8.0;
  for (const auto& [length, dphi] : segments) {
    const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
    for (int k = 1; k <= n; ++k) emit(tau + length * k / n, phi + dphi * k / n);
    tau += length;
    phi += dphi;
  }

  // Legs: from each puncture straight up, then into the knot along the axis.
  const double w = def.stitch_width_m;
  const Eigen::Vector3d p_first(-0.5 * w, 0.0, 0.0);
  const Eigen::Vector3d p_last(0.5 * w, 0.0, 0.0);
  auto leg = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    const double c = 0.4 * (q - p).norm();
    Eigen::Vector3d q1 = q - c * a;
    q1.z() = std::max(q1.z(), 0.5 * d);
    Curve out = {p};
    AppendBezier(p, p + c * Eigen::Vector3d::UnitZ(), q1, q, 64, out);
    out.pop_back();  // q is the knot's first point
    return out;
  };
  // Tails: on from the knot along the axis, away from it, then straight.
  auto tail = [&](const Eigen::Vector3d& p, double out_sign, double rise, double azimuth,
                  double elevation) {
    const Eigen::Vector3d dir = Direction(azimuth, elevation);
    const Eigen::Vector3d q1 = p + rise * a;
    const Eigen::Vector3d q2 = q1 + out_sign * 2.0 * d * radial(phi);
    const Eigen::Vector3d q3 = q2 + 2.0 * d * dir;
    Curve out;
    AppendBezier(p, q1, q2, q3, 48, out);
    out.push_back(q3 + def.tail_length_m * dir);
    return out;
  };
  Curve strand_a = leg(p_first, knot_a.front());
  strand_a.insert(strand_a.end(), knot_a.begin(), knot_a.end());
  const Curve tail_a =
      tail(knot_a.back(), -1.0, 2.0 * d, def.tail_first_azimuth_rad, def.tail_first_elevation_rad);
  strand_a.insert(strand_a.end(), tail_a.begin(), tail_a.end());
  Curve strand_b = leg(p_last, knot_b.front());
  strand_b.insert(strand_b.end(), knot_b.begin(), knot_b.end());
  const Curve tail_b =
      tail(knot_b.back(), 1.0, 4.0 * d, def.tail_last_azimuth_rad, def.tail_last_elevation_rad);
  strand_b.insert(strand_b.end(), tail_b.begin(), tail_b.end());

  // First free end -> first puncture -> stitch (half ellipse) -> last puncture -> last end.
  Curve dense(strand_a.rbegin(), strand_a.rend());
  const int stitch_samples = 96;
  for (int k = 1; k < stitch_samples; ++k) {
    const double theta = kPi * k / stitch_samples;
    dense.emplace_back(-0.5 * w * std::cos(theta), 0.0, -def.stitch_depth_m * std::sin(theta));
  }
  dense.insert(dense.end(), strand_b.begin(), strand_b.end());
  const double spacing = def.node_spacing_m > 0.0 ? def.node_spacing_m : d;
  Curve thread = ResampleOpen(dense, spacing);
  if (def.mirror) {
    for (auto& p : thread) p.y() = -p.y();
  }

  // The thread above the tissue stays above it, and no two parts of it touch.
  const int n = static_cast<int>(thread.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = thread[i];
    const bool in_stitch = std::abs(p.y()) < 1e-12 && p.z() <= 0.0 && std::abs(p.x()) <= 0.5 * w;
    if (!in_stitch && !(p.z() > 0.0)) {
      throw std::invalid_argument(
          "StitchKnotShapeDef.axis_tilt_rad: the knot or a tail would dip into the tissue");
    }
  }
  const double clearance = MinSelfDistance(thread, 2.5 * spacing);
  if (clearance < d) {
    throw std::invalid_argument("StitchKnotShapeDef.tail_*_azimuth_rad: the tails would pass " +
                                std::to_string(clearance / d) +
                                " diameters from the thread, less than one diameter");
  }
  return thread;
}

double MinSelfDistance(std::span<const Eigen::Vector3d> polyline, double skip_arc_m) {
  const int n = static_cast<int>(polyline.size());
  std::vector<double> s(n, 0.0);
  for (int i = 1; i < n; ++i) s[i] = s[i - 1] + (polyline[i] - polyline[i - 1]).norm();
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i + 1 < n; ++i) {
    const Eigen::Vector3d ci = 0.5 * (polyline[i] + polyline[i + 1]);
    const double ri = 0.5 * (polyline[i + 1] - polyline[i]).norm();
    for (int j = i + 1; j + 1 < n; ++j) {
      if (s[j] - s[i + 1] <= skip_arc_m) continue;
      const Eigen::Vector3d cj = 0.5 * (polyline[j] + polyline[j + 1]);
      const double rj = 0.5 * (polyline[j + 1] - polyline[j]).norm();
      if ((ci - cj).norm() - ri - rj >= best) continue;
      best = std::min(best, geometry::ClosestSegmentSegment(polyline[i], polyline[i + 1],
                                                            polyline[j], polyline[j + 1])
                                .distance_m);
    }
  }
  return best;
}

double PolylineLength(std::span<const Eigen::Vector3d> open) {
  double total = 0.0;
  for (std::size_t i = 0; i + 1 < open.size(); ++i) total += (open[i + 1] - open[i]).norm();
  return total;
}

std::vector<Eigen::Vector3d> ResampleByArcLength(std::span<const Eigen::Vector3d> open,
                                                 int segments) {
  MICRODEX_CHECK(open.size() >= 2 && segments >= 1);
  const double total = PolylineLength(open);
  const double h = total / segments;
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(segments) + 1);
  std::size_t i = 0;
  double s_i = 0.0;  // arc length at open[i]
  for (int k = 0; k <= segments; ++k) {
    const double s = std::min(k * h, total);
    while (i + 2 < open.size() && s_i + (open[i + 1] - open[i]).norm() < s) {
      s_i += (open[i + 1] - open[i]).norm();
      ++i;
    }
    const double len = (open[i + 1] - open[i]).norm();
    const double t = len > 0 ? std::clamp((s - s_i) / len, 0.0, 1.0) : 0.0;
    out.push_back(open[i] + t * (open[i + 1] - open[i]));
  }
  return out;
}

StitchKnotShapeDef QuizItemShapeDef(StitchKnotType kind, std::size_t index,
                                    double thread_diameter_m) {
  StitchKnotShapeDef def;
  def.kind = kind;
  def.thread_diameter_m = thread_diameter_m;
  const auto i = static_cast<double>(index);
  def.mirror = index % 2 == 1;
  def.axis_tilt_rad = 0.3 * static_cast<double>(index % 3);
  def.axis_azimuth_rad = 1.1 * i;
  def.tail_first_azimuth_rad = 3.14159 + 0.4 * static_cast<double>(index % 4);
  return def;
}

std::vector<Eigen::Vector3d> CropStitchTails(std::span<const Eigen::Vector3d> polyline,
                                             double radius_m) {
  const auto n = static_cast<std::ptrdiff_t>(polyline.size());
  std::ptrdiff_t first = -1, last = -1;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    if (polyline[static_cast<std::size_t>(i)].z() < 0) {
      if (first < 0) first = i;
      last = i;
    }
  }
  if (first < 0) return {polyline.begin(), polyline.end()};
  const Eigen::Vector3d a = polyline[static_cast<std::size_t>(first)];
  const Eigen::Vector3d b = polyline[static_cast<std::size_t>(last)];
  auto near = [&](std::ptrdiff_t i) {
    const Eigen::Vector3d& p = polyline[static_cast<std::size_t>(i)];
    return std::min((p - a).norm(), (p - b).norm()) <= radius_m;
  };
  std::ptrdiff_t begin = first;
  while (begin > 0 && near(begin - 1)) --begin;
  std::ptrdiff_t end = last;
  while (end + 1 < n && near(end + 1)) ++end;
  // Keep the first node beyond the radius on each side (the tails reach out of the knot).
  begin = std::max<std::ptrdiff_t>(begin - 1, 0);
  end = std::min<std::ptrdiff_t>(end + 1, n - 1);
  return {polyline.begin() + begin, polyline.begin() + end + 1};
}

double MedianLinkLength(std::span<const Eigen::Vector3d> polyline) {
  std::vector<double> lengths;
  lengths.reserve(polyline.size());
  for (std::size_t i = 0; i + 1 < polyline.size(); ++i) {
    const double l = (polyline[i + 1] - polyline[i]).norm();
    if (l > 0.0) lengths.push_back(l);
  }
  if (lengths.empty()) return 0.0;
  const auto mid = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
  std::nth_element(lengths.begin(), mid, lengths.end());
  return *mid;
}

Eigen::AlignedBox3d CalcStitchKnotCore(std::span<const Eigen::Vector3d> polyline,
                                       double thread_diameter_m, double contact_diameters) {
  Eigen::AlignedBox3d core;  // empty
  const std::size_t n = polyline.size();
  std::size_t first = n, last = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (polyline[i].z() < 0) {
      first = std::min(first, i);
      last = i;
    }
  }
  if (first == n || first < 2 || last + 2 >= n) return core;
  const double d = thread_diameter_m > 0 ? thread_diameter_m : MedianLinkLength(polyline);
  // The links above the tissue that touch or nearly touch (within contact_diameters) at an
  // angle of more than about 25 degrees (cos 0.9): the strands crossing each other and a strand
  // wound on itself, not the legs running side by side to the stitch nor neighbouring links.
  const double reach_m = contact_diameters * d;
  const auto in_strand = [&](std::size_t i) { return i + 1 < first || (i > last && i + 1 < n); };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!in_strand(i)) continue;
    const Eigen::Vector3d ta = polyline[i + 1] - polyline[i];
    for (std::size_t j = i + 3; j + 1 < n; ++j) {
      if (!in_strand(j)) continue;
      const Eigen::Vector3d tb = polyline[j + 1] - polyline[j];
      if (std::abs(ta.dot(tb)) > 0.9 * ta.norm() * tb.norm()) continue;
      const geometry::SegmentClosest c = geometry::ClosestSegmentSegment(
          polyline[i], polyline[i + 1], polyline[j], polyline[j + 1]);
      if (c.distance_m > reach_m || c.p.z() <= 0 || c.q.z() <= 0) continue;
      core.extend(c.p);
      core.extend(c.q);
    }
  }
  return core;
}

}  // namespace microdex::knot
