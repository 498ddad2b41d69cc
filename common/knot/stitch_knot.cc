// Stitch knots: split the thread at the tissue into its two strands, match them, follow the
// twist of the ribbon they span, cut it into throws, classify (README.md derives the method).
#include "common/knot/stitch_knot.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "common/knot/stitch_knot_shapes.h"

namespace microdex::knot {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr std::array<std::string_view, 7> kStitchNames = {
    "none", "square", "granny", "surgeons", "slip", "half-hitch", "unknown"};
// Strand samples per thread diameter.
constexpr double kSamplesPerDiameter = 2.0;
// Nodes inside the stitch may come this close above the surface (noise, a stitch grazing the
// surface) before the thread counts as passing through the tissue more than once.
constexpr double kStitchGraze_diameters = 1.0;

using Curve = std::vector<Eigen::Vector3d>;

// Equal arc-length samples of an open polyline at about `spacing` (both ends kept).
Curve Resample(std::span<const Eigen::Vector3d> open, double spacing) {
  return ResampleByArcLength(
      open, std::max(1, static_cast<int>(std::ceil(PolylineLength(open) / spacing))));
}

// Point where the segment [below, above] crosses z = 0.
Eigen::Vector3d Puncture(const Eigen::Vector3d& below, const Eigen::Vector3d& above) {
  const double t = below.z() / (below.z() - above.z());
  Eigen::Vector3d p = below + t * (above - below);
  p.z() = 0.0;
  return p;
}

// Monotone matching of two sampled strands (dynamic time warping on the distance): pairs
// (i, j) from (0, 0) to (na - 1, nb - 1), each step advancing i, j or both.
std::vector<std::pair<int, int>> MatchStrands(const Curve& a, const Curve& b) {
  const int na = static_cast<int>(a.size());
  const int nb = static_cast<int>(b.size());
  std::vector<std::uint8_t> step(static_cast<std::size_t>(na) * nb);
  std::vector<double> prev(nb);
  std::vector<double> row(nb);
  for (int i = 0; i < na; ++i) {
    for (int j = 0; j < nb; ++j) {
      const double c = (a[i] - b[j]).norm();
      // Symmetric weights (a diagonal step counts its cost twice): every path then weighs
      // na + nb - 2 costs, so a strand wound around a straight one (three times longer over
      // the hitch) is matched turn by turn instead of cut short.
      double best = 0.0;
      std::uint8_t from = 0;
      if (i == 0 && j == 0) {
        best = c;
      } else if (i == 0) {
        best = row[j - 1] + c;
        from = 2;
      } else if (j == 0) {
        best = prev[j] + c;
        from = 1;
      } else {
        best = prev[j - 1] + 2.0 * c;
        from = 3;
        if (prev[j] + c < best) {
          best = prev[j] + c;
          from = 1;
        }
        if (row[j - 1] + c < best) {
          best = row[j - 1] + c;
          from = 2;
        }
      }
      row[j] = best;
      step[static_cast<std::size_t>(i) * nb + j] = from;
    }
    std::swap(prev, row);
  }
  std::vector<std::pair<int, int>> path;
  int i = na - 1;
  int j = nb - 1;
  for (;;) {
    path.emplace_back(i, j);
    const std::uint8_t from = step[static_cast<std::size_t>(i) * nb + j];
    if (from == 0) break;
    if (from & 1) --i;
    if (from & 2) --j;
  }
  std::reverse(path.begin(), path.end());
  return path;
}

// Signed angle from u to v about the unit axis t (both roughly normal to t).
double SignedAngle(const Eigen::Vector3d& u, const Eigen::Vector3d& v, const Eigen::Vector3d& t) {
  return std::atan2(u.cross(v).dot(t), u.dot(v));
}

struct Run {
  int first = 0;  // path sample indices
  int last = 0;
  double twist = 0.0;
};

// Cuts the twisting stretches of the cumulative twist `tw` into runs of one sense. Stretches
// separated by less than `min_quiet` of axis (`sigma`) are one stretch; inside a stretch a
// run ends where the twist turns back by `reversal` or more.
std::vector<Run> TwistRuns(const std::vector<double>& tw, const std::vector<double>& sigma,
                           const std::vector<bool>& twisting, double min_quiet, double reversal) {
  const int n = static_cast<int>(tw.size());
  std::vector<std::pair<int, int>> stretches;
  for (int k = 0; k < n;) {
    if (!twisting[k]) {
      ++k;
      continue;
    }
    int end = k;
    while (end + 1 < n && twisting[end + 1]) ++end;
    if (!stretches.empty() && sigma[k] - sigma[stretches.back().second] < min_quiet) {
      stretches.back().second = end;
    } else {
      stretches.emplace_back(k, end);
    }
    k = end + 1;
  }
  std::vector<Run> runs;
  for (const auto& [first, end] : stretches) {
    int start = first;
    int extreme = first;
    int sense = 0;
    for (int q = first + 1; q <= end; ++q) {
      if (sense == 0) {
        if (std::abs(tw[q] - tw[start]) >= reversal) {
          sense = tw[q] > tw[start] ? 1 : -1;
          extreme = q;
        }
        continue;
      }
      const double change = tw[q] - tw[extreme];
      if (sense * change > 0) {
        extreme = q;
      } else if (-sense * change >= reversal) {
        runs.push_back({start, extreme, tw[extreme] - tw[start]});
        start = extreme;
        extreme = q;
        sense = -sense;
      }
    }
    // The last run ends at its extreme value (a small return after it is not part of it).
    const int last = sense == 0 ? end : extreme;
    runs.push_back({start, last, tw[last] - tw[start]});
  }
  return runs;
}

StitchKnotType Classify(const std::vector<StitchThrow>& throws, double total_twist,
                        std::string* reason) {
  if (throws.empty()) return StitchKnotType::kNone;
  const bool all_hitches = std::all_of(throws.begin(), throws.end(), [&](const StitchThrow& t) {
    return t.hitch && t.post_strand == throws.front().post_strand;
  });
  const bool no_hitch =
      std::none_of(throws.begin(), throws.end(), [](const StitchThrow& t) { return t.hitch; });
  if (all_hitches) {
    const bool single_turns = std::all_of(throws.begin(), throws.end(),
                                          [](const StitchThrow& t) { return t.turns == 1; });
    if (single_turns && throws.size() == 1) return StitchKnotType::kHalfHitch;
    if (single_turns && throws.size() == 2) return StitchKnotType::kSlip;
    *reason = "half hitches that are not one or two single turns around one post";
    return StitchKnotType::kUnknown;
  }
  if (!no_hitch) {
    *reason = "throws mixed with half hitches, or hitches on both strands";
    return StitchKnotType::kUnknown;
  }
  if (throws.size() == 2) {
    const StitchThrow& a = throws[0];
    const StitchThrow& b = throws[1];
    if (a.turns == 1 && b.turns == 1) {
      // The total twist is the tangle's invariant (README.md): about 0 turns for a square,
      // +-2 for a granny. A run structure that disagrees with it is not trusted.
      const bool same = a.hand == b.hand;
      if (same == (std::abs(total_twist) > 1.0)) {
        return same ? StitchKnotType::kGranny : StitchKnotType::kSquare;
      }
      *reason = "the throws' hands disagree with the total twist";
      return StitchKnotType::kUnknown;
    }
    if (a.turns == 2 && b.turns == 1 && a.hand != b.hand) return StitchKnotType::kSurgeons;
  }
  *reason = std::to_string(throws.size()) + " throw(s) that make none of the classes";
  return StitchKnotType::kUnknown;
}

// A knot tied by passing ends through loops: its closure names it; the twist runs tell only
// whether it capsized into half hitches on one straight strand (a slip knot, a lone half
// hitch), which the closure cannot see (capsizing keeps the ends where they are).
StitchKnotType ClassifyTied(KnotType closure, const std::vector<StitchThrow>& throws,
                            std::string* reason) {
  const bool hitches_on_one_post =
      !throws.empty() && std::all_of(throws.begin(), throws.end(), [&](const StitchThrow& t) {
        return t.hitch && t.turns == 1 && t.post_strand == throws.front().post_strand;
      });
  switch (closure) {
    case KnotType::kSquare:
    case KnotType::kGranny:
      if (hitches_on_one_post && throws.size() == 2) return StitchKnotType::kSlip;
      return closure == KnotType::kSquare ? StitchKnotType::kSquare : StitchKnotType::kGranny;
    case KnotType::kSurgeons:
      return StitchKnotType::kSurgeons;
    case KnotType::kOverhandLeft:
    case KnotType::kOverhandRight:
      if (hitches_on_one_post && throws.size() == 1) return StitchKnotType::kHalfHitch;
      *reason = "a lone throw (the closure is a trefoil)";
      return StitchKnotType::kUnknown;
    default:
      *reason = "the closure is " + std::string(KnotName(closure)) + ", not a surgical knot";
      return StitchKnotType::kUnknown;
  }
}

}  // namespace

std::string_view StitchKnotName(StitchKnotType type) {
  return kStitchNames[static_cast<int>(type)];
}

std::optional<StitchKnotType> StitchKnotTypeFromName(std::string_view name) {
  for (std::size_t i = 0; i < kStitchNames.size(); ++i) {
    if (kStitchNames[i] == name) return static_cast<StitchKnotType>(i);
  }
  return std::nullopt;
}

void StitchKnotOptions::Validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!std::isfinite(thread_diameter_m) || thread_diameter_m < 0.0) {
    throw std::invalid_argument(
        "StitchKnotOptions.thread_diameter_m: expected a finite value >= 0");
  }
  if (!positive(contact_diameters)) {
    throw std::invalid_argument("StitchKnotOptions.contact_diameters: expected > 0");
  }
  if (!positive(axis_window_diameters)) {
    throw std::invalid_argument("StitchKnotOptions.axis_window_diameters: expected > 0");
  }
  if (!positive(rate_window_diameters)) {
    throw std::invalid_argument("StitchKnotOptions.rate_window_diameters: expected > 0");
  }
  if (!positive(rate_threshold_turns)) {
    throw std::invalid_argument("StitchKnotOptions.rate_threshold_turns: expected > 0");
  }
  if (!std::isfinite(min_quiet_diameters) || min_quiet_diameters < 0.0) {
    throw std::invalid_argument("StitchKnotOptions.min_quiet_diameters: expected >= 0");
  }
  if (!positive(reversal_turns)) {
    throw std::invalid_argument("StitchKnotOptions.reversal_turns: expected > 0");
  }
  if (!positive(min_throw_turns)) {
    throw std::invalid_argument("StitchKnotOptions.min_throw_turns: expected > 0");
  }
  if (!(hitch_length_ratio > 0.0 && hitch_length_ratio <= 1.0)) {
    throw std::invalid_argument("StitchKnotOptions.hitch_length_ratio: expected in (0, 1]");
  }
  if (!(post_straightness > 0.0 && post_straightness <= 1.0)) {
    throw std::invalid_argument("StitchKnotOptions.post_straightness: expected in (0, 1]");
  }
}

bool IsStitchPolyline(std::span<const Eigen::Vector3d> polyline) {
  if (polyline.size() < 2 || !(polyline.front().z() > 0.0) || !(polyline.back().z() > 0.0)) {
    return false;
  }
  return std::any_of(polyline.begin(), polyline.end(),
                     [](const Eigen::Vector3d& p) { return p.z() < 0.0; });
}

double GaussLinkingIntegral(std::span<const Eigen::Vector3d> a,
                            std::span<const Eigen::Vector3d> b) {
  // Solid angle of the quadrilateral seen between two segments (Klenin & Langowski 2000,
  // Biopolymers 54:307, eq. 16).
  auto unit_cross = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    const Eigen::Vector3d c = u.cross(v);
    const double n = c.norm();
    return n > 0.0 ? Eigen::Vector3d(c / n) : Eigen::Vector3d::Zero();
  };
  auto safe_asin = [](double x) { return std::asin(std::clamp(x, -1.0, 1.0)); };
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < a.size(); ++i) {
    const Eigen::Vector3d& p1 = a[i];
    const Eigen::Vector3d& p2 = a[i + 1];
    for (std::size_t j = 0; j + 1 < b.size(); ++j) {
      const Eigen::Vector3d& p3 = b[j];
      const Eigen::Vector3d& p4 = b[j + 1];
      const Eigen::Vector3d r13 = p3 - p1;
      const Eigen::Vector3d r14 = p4 - p1;
      const Eigen::Vector3d r23 = p3 - p2;
      const Eigen::Vector3d r24 = p4 - p2;
      const Eigen::Vector3d n1 = unit_cross(r13, r14);
      const Eigen::Vector3d n2 = unit_cross(r14, r24);
      const Eigen::Vector3d n3 = unit_cross(r24, r23);
      const Eigen::Vector3d n4 = unit_cross(r23, r13);
      const double omega = safe_asin(n1.dot(n2)) + safe_asin(n2.dot(n3)) + safe_asin(n3.dot(n4)) +
                           safe_asin(n4.dot(n1));
      const double orient = (p4 - p3).cross(p2 - p1).dot(r13);
      if (orient != 0.0) sum += orient > 0 ? omega : -omega;
    }
  }
  return sum / (4.0 * kPi);
}

StitchKnotAnalysis AnalyzeStitchKnot(std::span<const Eigen::Vector3d> polyline,
                                     const StitchKnotOptions& options) {
  options.Validate();
  const int n = static_cast<int>(polyline.size());
  if (n < 4) {
    throw std::invalid_argument("stitch polyline: " + std::to_string(n) +
                                " node(s), expected at least 4");
  }
  for (int i = 0; i < n; ++i) {
    if (!polyline[i].allFinite()) {
      throw std::invalid_argument("stitch polyline: node " + std::to_string(i) + " is not finite");
    }
  }
  if (!(polyline.front().z() > 0.0) || !(polyline.back().z() > 0.0)) {
    throw std::invalid_argument(
        "stitch polyline: both end nodes must lie above the tissue (z > 0)");
  }
  StitchKnotAnalysis out;
  for (int i = 0; i < n; ++i) {
    if (polyline[i].z() < 0.0) {
      if (out.first_below < 0) out.first_below = i;
      out.last_below = i;
    }
  }
  if (out.first_below < 0) {
    throw std::invalid_argument("stitch polyline: no node below the tissue (z < 0)");
  }
  // Thread diameter: given, or the median link length.
  double diameter = options.thread_diameter_m;
  if (diameter <= 0.0) {
    diameter = MedianLinkLength(polyline);
    if (diameter <= 0.0) throw std::invalid_argument("stitch polyline: all nodes coincide");
  }
  out.thread_diameter_m = diameter;

  // The two strands, each from its puncture outwards to its free end.
  Curve strand_a;
  Curve strand_b;
  out.p_puncture_first_W = Puncture(polyline[out.first_below], polyline[out.first_below - 1]);
  out.p_puncture_last_W = Puncture(polyline[out.last_below], polyline[out.last_below + 1]);
  strand_a.push_back(out.p_puncture_first_W);
  for (int i = out.first_below - 1; i >= 0; --i) strand_a.push_back(polyline[i]);
  strand_b.push_back(out.p_puncture_last_W);
  for (int i = out.last_below + 1; i < n; ++i) strand_b.push_back(polyline[i]);

  out.closure = RecognizeKnot(polyline);
  if (options.full_evidence) out.gauss_linking = GaussLinkingIntegral(strand_a, strand_b);

  for (int i = out.first_below; i <= out.last_below; ++i) {
    if (polyline[i].z() > kStitchGraze_diameters * diameter) {
      out.reason = "the thread passes through the tissue more than once";
      return out;
    }
  }

  // Match the strands and follow the twist of the ribbon they span.
  const double h = diameter / kSamplesPerDiameter;
  const Curve a = Resample(strand_a, h);
  const Curve b = Resample(strand_b, h);
  const std::vector<std::pair<int, int>> path = MatchStrands(a, b);
  const int m = static_cast<int>(path.size());
  std::vector<Eigen::Vector3d> mid(m);
  std::vector<Eigen::Vector3d> gap(m);
  std::vector<double> sigma(m, 0.0);  // arc length along the midline
  for (int k = 0; k < m; ++k) {
    mid[k] = 0.5 * (a[path[k].first] + b[path[k].second]);
    gap[k] = b[path[k].second] - a[path[k].first];
    if (k > 0) sigma[k] = sigma[k - 1] + (mid[k] - mid[k - 1]).norm();
  }
  // Common axis: the midline averaged over +-window of its arc length (prefix sums), which
  // removes the wobble of a half hitch's midline around the post.
  const double window = options.axis_window_diameters * diameter;
  std::vector<Eigen::Vector3d> prefix(m + 1, Eigen::Vector3d::Zero());
  for (int k = 0; k < m; ++k) prefix[k + 1] = prefix[k] + mid[k];
  std::vector<Eigen::Vector3d> axis_point(m);
  {
    int lo = 0;
    int hi = 0;
    for (int k = 0; k < m; ++k) {
      while (sigma[lo] < sigma[k] - window) ++lo;
      while (hi + 1 < m && sigma[hi + 1] <= sigma[k] + window) ++hi;
      axis_point[k] = (prefix[hi + 1] - prefix[lo]) / (hi - lo + 1);
    }
  }
  std::vector<Eigen::Vector3d> tangent(m, Eigen::Vector3d::UnitZ());
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector3d d = axis_point[std::min(k + 1, m - 1)] - axis_point[std::max(k - 1, 0)];
    if (d.norm() > 1e-9 * diameter) {
      tangent[k] = d.normalized();
    } else if (k > 0) {
      tangent[k] = tangent[k - 1];
    }
  }
  const double contact = options.contact_diameters * diameter;
  std::vector<double> twist(m, 0.0);  // cumulative, in turns
  for (int k = 1; k < m; ++k) {
    twist[k] = twist[k - 1];
    if (gap[k].norm() > contact || gap[k - 1].norm() > contact) continue;
    const Eigen::Vector3d e0 = gap[k - 1] - gap[k - 1].dot(tangent[k - 1]) * tangent[k - 1];
    const Eigen::Vector3d e1 = gap[k] - gap[k].dot(tangent[k]) * tangent[k];
    if (e0.norm() < 0.1 * gap[k - 1].norm() || e1.norm() < 0.1 * gap[k].norm()) continue;
    // Parallel transport of e0 from the previous axis direction to this one.
    const Eigen::Vector3d moved =
        Eigen::Quaterniond::FromTwoVectors(tangent[k - 1], tangent[k]) * e0;
    twist[k] += SignedAngle(moved, e1, tangent[k]) / (2.0 * kPi);
  }
  out.total_twist_turns = twist.back();

  // Twisting where the twist changes by more than the threshold over the rate window.
  std::vector<bool> twisting(m, false);
  {
    const double half = 0.5 * options.rate_window_diameters * diameter;
    int lo = 0;
    int hi = 0;
    for (int k = 0; k < m; ++k) {
      while (sigma[lo] < sigma[k] - half) ++lo;
      while (hi + 1 < m && sigma[hi + 1] <= sigma[k] + half) ++hi;
      twisting[k] = std::abs(twist[hi] - twist[lo]) > options.rate_threshold_turns;
    }
  }
  std::vector<Run> runs = TwistRuns(twist, sigma, twisting, options.min_quiet_diameters * diameter,
                                    options.reversal_turns);
  runs.erase(
      std::remove_if(runs.begin(), runs.end(),
                     [&](const Run& r) { return std::abs(r.twist) < options.min_throw_turns; }),
      runs.end());
  // A run's twist is counted from the middle of the quiet stretch before it to the middle of
  // the one after it: the slow start and end of a turn belong to the run.
  for (std::size_t q = 0; q < runs.size(); ++q) {
    const int from = q == 0 ? runs[q].first : (runs[q - 1].last + runs[q].first) / 2;
    const int to = q + 1 == runs.size() ? runs[q].last : (runs[q].last + runs[q + 1].first) / 2;
    runs[q].twist = twist[to] - twist[from];
  }
  for (const Run& r : runs) {
    StitchThrow t;
    t.twist_turns = r.twist;
    t.hand = r.twist > 0 ? 1 : -1;
    t.turns = std::max(1, static_cast<int>(std::lround(std::abs(r.twist))));
    const int i0 = path[r.first].first;
    const int i1 = path[r.last].first;
    const int j0 = path[r.first].second;
    const int j1 = path[r.last].second;
    const double len_a = (i1 - i0) * h;
    const double len_b = (j1 - j0) * h;
    const double longer = std::max(len_a, len_b);
    t.length_ratio = longer > 0 ? std::min(len_a, len_b) / longer : 1.0;
    t.straightness[0] = len_a > 0 ? (a[i1] - a[i0]).norm() / len_a : 1.0;
    t.straightness[1] = len_b > 0 ? (b[j1] - b[j0]).norm() / len_b : 1.0;
    const int post = t.straightness[0] >= t.straightness[1] ? 1 : 2;
    t.hitch = t.length_ratio < options.hitch_length_ratio &&
              t.straightness[post - 1] >= options.post_straightness;
    if (t.hitch) t.post_strand = post;
    t.start_s_m = i0 * h;
    t.end_s_m = i1 * h;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = r.first; k <= r.last; ++k) c += mid[k];
    t.p_center_W = c / (r.last - r.first + 1);
    out.throws.push_back(t);
  }
  if (out.closure == KnotType::kNone) {
    out.type = Classify(out.throws, out.total_twist_turns, &out.reason);
  } else {
    out.from_closure = true;
    out.type = ClassifyTied(out.closure, out.throws, &out.reason);
  }
  return out;
}

StitchKnotType RecogniseStitchKnot(std::span<const Eigen::Vector3d> polyline,
                                   const StitchKnotOptions& options) {
  StitchKnotOptions fast = options;
  fast.full_evidence = false;
  return AnalyzeStitchKnot(polyline, fast).type;
}

}  // namespace microdex::knot
