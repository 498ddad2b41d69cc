// Knot recognition pipeline: prepare -> close -> reduce -> project (several directions) ->
// Reidemeister I/II -> invariants -> vote -> classify -> locate the knotted core.
#include "common/knot/recognition.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "common/base/check.h"
#include "common/knot/closure.h"
#include "common/knot/diagram.h"
#include "common/knot/invariants.h"
#include "common/knot/projection.h"
#include "common/knot/reduction.h"
#include "common/knot/stitch_knot_shapes.h"

namespace microdex::knot {
namespace {

constexpr std::array<std::string_view, 9> kKnotNames = {
    "none",   "overhand-left", "overhand-right", "double-overhand", "figure-eight",
    "square", "granny",        "surgeons",       "unknown"};

// Consecutive nodes closer than this fraction of the thread's extent are merged.
constexpr double kDuplicateRelTol = 1e-12;
// Diagrams with more crossings after Reidemeister I/II are not classified (unknown).
constexpr int kMaxClassifiedCrossings = 60;
// Projection attempts per requested projection before giving up (non-generic directions).
constexpr int kAttemptsPerProjection = 8;

// The exact invariants of one projection.
struct ProjectionInvariants {
  knot::GaussCode code;  // after Reidemeister I/II
  int raw_crossings = 0;
  LaurentPolynomial alexander;
  int signature = 0;
  std::int64_t determinant = 0;
  bool Agrees(const ProjectionInvariants& o) const {
    return alexander == o.alexander && signature == o.signature;
  }
};

// A class of the table: its Alexander polynomial, signature and Jones polynomial.
struct KnotClass {
  KnotType type;
  LaurentPolynomial alexander;
  int signature;
  LaurentPolynomial jones;
};

// Invariants of the classified knots (README.md derives them). Right-handed trefoil
// V = t + t^3 - t^4 (Jones' skein relation with L+ a positive crossing). The double
// overhand closes to the cinquefoil 5_1 = T(2,5) (an end passed twice through the loop is a
// 2-braid with five crossings); positive: V = t^2 + t^4 - t^5 + t^6 - t^7, signature -4.
// Connected sums multiply both polynomials and add signatures; the square and the surgeon's
// knot pair components of opposite handedness.
const std::vector<KnotClass>& KnotTable() {
  static const std::vector<KnotClass> table = [] {
    using knot::Mirror;
    using knot::Multiply;
    const LaurentPolynomial one{0, {1}};
    const LaurentPolynomial a31{-1, {1, -1, 1}};
    const LaurentPolynomial a41{-1, {1, -3, 1}};
    const LaurentPolynomial a51{-2, {1, -1, 1, -1, 1}};
    const LaurentPolynomial v31r{1, {1, 0, 1, -1}};
    const LaurentPolynomial v31l = Mirror(v31r);
    const LaurentPolynomial v41{-2, {1, -1, 1, -1, 1}};
    const LaurentPolynomial v51r{2, {1, 0, 1, -1, 1, -1}};
    const LaurentPolynomial v51l = Mirror(v51r);
    const LaurentPolynomial a_sum33 = Multiply(a31, a31);
    const LaurentPolynomial a_sum53 = Multiply(a51, a31);
    return std::vector<KnotClass>{
        {KnotType::kNone, one, 0, one},
        {KnotType::kOverhandRight, a31, -2, v31r},
        {KnotType::kOverhandLeft, a31, 2, v31l},
        {KnotType::kFigureEight, a41, 0, v41},
        {KnotType::kDoubleOverhand, a51, -4, v51r},
        {KnotType::kDoubleOverhand, a51, 4, v51l},
        {KnotType::kSquare, a_sum33, 0, Multiply(v31r, v31l)},
        {KnotType::kGranny, a_sum33, -4, Multiply(v31r, v31r)},
        {KnotType::kGranny, a_sum33, 4, Multiply(v31l, v31l)},
        {KnotType::kSurgeons, a_sum53, -2, Multiply(v51r, v31l)},
        {KnotType::kSurgeons, a_sum53, 2, Multiply(v51l, v31r)},
    };
  }();
  return table;
}

KnotType Classify(const KnotAnalysis& a) {
  // Alexander polynomial and signature of a class but another Jones polynomial: not that knot.
  for (const KnotClass& k : KnotTable()) {
    if (k.alexander != a.alexander || k.signature != a.signature) continue;
    if (!a.jones_computed || k.jones == a.jones) return k.type;
  }
  return KnotType::kUnknown;
}

// Validated nodes with consecutive duplicates merged.
std::vector<Eigen::Vector3d> PrepareNodes(std::span<const Eigen::Vector3d> polyline) {
  if (polyline.size() < 2) {
    throw std::invalid_argument("knot polyline: " + std::to_string(polyline.size()) +
                                " node(s), expected at least 2");
  }
  Eigen::AlignedBox3d box;
  for (std::size_t i = 0; i < polyline.size(); ++i) {
    if (!polyline[i].allFinite()) {
      throw std::invalid_argument("knot polyline: node " + std::to_string(i) + " is not finite");
    }
    box.extend(polyline[i]);
  }
  const double tol = kDuplicateRelTol * box.sizes().maxCoeff();
  std::vector<Eigen::Vector3d> nodes;
  nodes.reserve(polyline.size());
  for (const auto& p : polyline) {
    if (nodes.empty() || (p - nodes.back()).norm() > tol) nodes.push_back(p);
  }
  if (nodes.size() < 2) {
    throw std::invalid_argument("knot polyline: all nodes coincide, expected two distinct nodes");
  }
  return nodes;
}

Eigen::Vector3d RandomDirection(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (;;) {
    const Eigen::Vector3d v(uniform(rng), uniform(rng), uniform(rng));
    const double n = v.norm();
    if (n > 0.1 && n <= 1.0) return v / n;
  }
}

// Closed, reduced polygon of an open thread.
std::vector<Eigen::Vector3d> ReducedClosure(std::span<const Eigen::Vector3d> nodes,
                                            double diameter_m, bool reduce = true) {
  std::vector<Eigen::Vector3d> closed = knot::CloseThread(nodes, diameter_m);
  if (!reduce) return closed;
  const std::vector<int> kept = knot::ReducePolygon(closed);
  std::vector<Eigen::Vector3d> reduced;
  reduced.reserve(kept.size());
  for (int i : kept) reduced.push_back(closed[i]);
  return reduced;
}

std::optional<ProjectionInvariants> InvariantsAlong(std::span<const Eigen::Vector3d> polygon,
                                                    const Eigen::Vector3d& direction) {
  std::optional<knot::GaussCode> raw = knot::ProjectPolygon(polygon, direction);
  if (!raw) return std::nullopt;
  ProjectionInvariants inv;
  inv.raw_crossings = raw->num_crossings();
  inv.code = knot::SimplifyReidemeister(*raw);
  // Beyond this the O(n^4) exact Alexander polynomial would take too long; such a tangle is
  // none of the classes anyway (their diagrams reduce to at most 8 crossings).
  if (inv.code.num_crossings() > kMaxClassifiedCrossings) return std::nullopt;
  const knot::PlanarDiagram pd = knot::MakePlanarDiagram(inv.code);
  inv.alexander = knot::AlexanderPolynomial(pd);
  const knot::GoeritzResult g = knot::GoeritzSignature(pd);
  inv.signature = g.signature;
  inv.determinant = g.determinant;
  // |Delta(-1)| = |det G|: two independent computations of the determinant must agree.
  if (inv.alexander.coefficients.empty() ||
      std::llabs(knot::EvaluateAtPlusMinusOne(inv.alexander, -1)) != g.determinant) {
    return std::nullopt;
  }
  return inv;
}

// Invariants of a reduced polygon seen along `count` random directions, majority group first.
std::vector<ProjectionInvariants> VoteInvariants(std::span<const Eigen::Vector3d> polygon,
                                                 int count, std::mt19937_64& rng, int* tried) {
  std::vector<ProjectionInvariants> results;
  *tried = 0;
  if (polygon.size() <= 3) {
    ProjectionInvariants trivial;
    trivial.alexander = LaurentPolynomial{0, {1}};
    trivial.determinant = 1;
    results.push_back(trivial);
    *tried = 1;
    return results;
  }
  for (int attempt = 0;
       attempt < kAttemptsPerProjection * count && static_cast<int>(results.size()) < count;
       ++attempt) {
    ++*tried;
    if (auto inv = InvariantsAlong(polygon, RandomDirection(rng))) results.push_back(*inv);
  }
  // Move the largest group of agreeing projections to the front, fewest crossings first.
  std::size_t best = 0;
  std::size_t best_votes = 0;
  for (std::size_t i = 0; i < results.size(); ++i) {
    std::size_t votes = 0;
    for (const auto& r : results) votes += results[i].Agrees(r) ? 1 : 0;
    if (votes > best_votes) {
      best_votes = votes;
      best = i;
    }
  }
  if (results.empty()) return results;
  const ProjectionInvariants winner = results[best];
  std::stable_partition(results.begin(), results.end(),
                        [&](const ProjectionInvariants& r) { return r.Agrees(winner); });
  std::sort(results.begin(), results.begin() + static_cast<long>(best_votes),
            [](const ProjectionInvariants& a, const ProjectionInvariants& b) {
              return a.code.num_crossings() < b.code.num_crossings();
            });
  return results;
}

bool IsTrivial(const ProjectionInvariants& inv) {
  return inv.alexander == LaurentPolynomial{0, {1}} && inv.signature == 0;
}

}  // namespace

std::string_view KnotName(KnotType type) { return kKnotNames[static_cast<int>(type)]; }

std::optional<KnotType> KnotTypeFromName(std::string_view name) {
  for (std::size_t i = 0; i < kKnotNames.size(); ++i) {
    if (kKnotNames[i] == name) return static_cast<KnotType>(i);
  }
  return std::nullopt;
}

void KnotOptions::Validate() const {
  if (!(thread_diameter_m >= 0.0) || !std::isfinite(thread_diameter_m)) {
    throw std::invalid_argument("KnotOptions.thread_diameter_m: expected a finite value >= 0");
  }
  if (num_projections < 1 || num_projections > 64) {
    throw std::invalid_argument("KnotOptions.num_projections: expected 1..64");
  }
  if (max_jones_crossings < 0 || max_jones_crossings > 24) {
    throw std::invalid_argument("KnotOptions.max_jones_crossings: expected 0..24");
  }
}

KnotAnalysis AnalyzeKnot(std::span<const Eigen::Vector3d> polyline, const KnotOptions& options) {
  options.Validate();
  const std::vector<Eigen::Vector3d> nodes = PrepareNodes(polyline);
  const double diameter =
      options.thread_diameter_m > 0.0 ? options.thread_diameter_m : MedianLinkLength(nodes);
  std::mt19937_64 rng(options.seed);

  KnotAnalysis analysis;
  const std::vector<Eigen::Vector3d> reduced =
      ReducedClosure(nodes, diameter, options.reduce_polygon);
  analysis.reduced_vertices = static_cast<int>(reduced.size());
  int tried = 0;
  const std::vector<ProjectionInvariants> votes =
      VoteInvariants(reduced, options.num_projections, rng, &tried);
  analysis.projections_tried = tried;
  if (votes.empty()) return analysis;  // no generic projection: unknown
  const ProjectionInvariants& winner = votes.front();
  for (const auto& v : votes) analysis.projections_agreeing += winner.Agrees(v) ? 1 : 0;
  analysis.raw_crossings = winner.raw_crossings;
  analysis.crossings = winner.code.num_crossings();
  analysis.alexander = winner.alexander;
  analysis.signature = winner.signature;
  analysis.determinant = winner.determinant;
  if (analysis.crossings <= options.max_jones_crossings) {
    analysis.jones = knot::JonesPolynomial(knot::MakePlanarDiagram(winner.code));
    analysis.jones_computed = true;
  }
  // A strict majority of the projections must agree.
  const int successful = static_cast<int>(votes.size());
  analysis.type =
      2 * analysis.projections_agreeing > successful ? Classify(analysis) : KnotType::kUnknown;

  if (options.locate && !IsTrivial(winner)) {
    // Knotted core: the shortest sub-arc [first, last] with the whole thread's invariants,
    // found by bisection from each end (cutting a tail off keeps the knot until the cut
    // enters the core).
    const int n = static_cast<int>(nodes.size());
    auto knotted = [&](int first, int last) {
      if (last - first < 3) return false;
      const std::span<const Eigen::Vector3d> arc(nodes.data() + first, last - first + 1);
      int arc_tried = 0;
      const auto arc_votes = VoteInvariants(ReducedClosure(arc, diameter), 1, rng, &arc_tried);
      return !arc_votes.empty() && arc_votes.front().Agrees(winner);
    };
    int lo = 0;
    int hi = n - 1;
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      (knotted(mid, n - 1) ? lo : hi) = mid;
    }
    const int first = lo;
    lo = first;
    hi = n - 1;
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      (knotted(first, mid) ? hi : lo) = mid;
    }
    const int last = hi;
    double s = 0.0;
    double weight = 0.0;
    Eigen::Vector3d weighted = Eigen::Vector3d::Zero();
    for (int i = 0; i < last; ++i) {
      const double len = (nodes[i + 1] - nodes[i]).norm();
      if (i == first) analysis.core_start_s_m = s;
      if (i >= first) {
        weighted += len * 0.5 * (nodes[i] + nodes[i + 1]);
        weight += len;
      }
      s += len;
    }
    analysis.core_end_s_m = s;
    analysis.p_core_W = weight > 0 ? Eigen::Vector3d(weighted / weight) : nodes[first];
    analysis.located = true;
  }
  return analysis;
}

KnotType RecognizeKnot(std::span<const Eigen::Vector3d> polyline, const KnotOptions& options) {
  KnotOptions recognize_only = options;
  recognize_only.locate = false;
  return AnalyzeKnot(polyline, recognize_only).type;
}

void KnotTargetDef::Validate() const {
  if (!p_axis_W.allFinite()) throw std::invalid_argument("KnotTargetDef.p_axis_W: not finite");
  if (!axis_W.allFinite() || axis_W.norm() <= 0.0) {
    throw std::invalid_argument("KnotTargetDef.axis_W: expected a finite non-zero vector");
  }
  const Eigen::Vector3d a = axis_W.normalized();
  if (!ref_W.allFinite() || (ref_W - ref_W.dot(a) * a).norm() <= 1e-9 * ref_W.norm() ||
      ref_W.norm() <= 0.0) {
    throw std::invalid_argument(
        "KnotTargetDef.ref_W: expected a finite vector not parallel to axis_W");
  }
  if (edge_W.empty()) throw std::invalid_argument("KnotTargetDef.edge_W: expected >= 1 point");
  for (const auto& p : edge_W) {
    if (!p.allFinite()) throw std::invalid_argument("KnotTargetDef.edge_W: point not finite");
  }
}

KnotPlacement CalcKnotPlacement(const KnotAnalysis& analysis, const KnotTargetDef& target) {
  target.Validate();
  if (!analysis.located) {
    throw std::invalid_argument("CalcKnotPlacement: the analysis has no located knot");
  }
  KnotPlacement out;
  out.core_start_s_m = analysis.core_start_s_m;
  out.core_end_s_m = analysis.core_end_s_m;
  out.core_center_s_m = 0.5 * (analysis.core_start_s_m + analysis.core_end_s_m);
  out.p_core_W = analysis.p_core_W;
  const Eigen::Vector3d& p = analysis.p_core_W;
  // Distance to the edge polyline.
  double best = (p - target.edge_W.front()).norm();
  for (std::size_t i = 0; i + 1 < target.edge_W.size(); ++i) {
    const Eigen::Vector3d a = target.edge_W[i];
    const Eigen::Vector3d ab = target.edge_W[i + 1] - a;
    const double l2 = ab.squaredNorm();
    const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - p).norm());
  }
  if (target.edge_W.size() > 1) best = std::min(best, (p - target.edge_W.back()).norm());
  out.distance_to_edge_m = best;
  // Cylindrical coordinates about the vessel axis.
  const Eigen::Vector3d axis = target.axis_W.normalized();
  const Eigen::Vector3d e1 = (target.ref_W - target.ref_W.dot(axis) * axis).normalized();
  const Eigen::Vector3d e2 = axis.cross(e1);
  const Eigen::Vector3d w = p - target.p_axis_W;
  out.axial_position_m = w.dot(axis);
  const double x = w.dot(e1);
  const double y = w.dot(e2);
  out.radial_distance_m = std::hypot(x, y);
  out.angle_around_axis_rad = std::atan2(y, x);
  if (out.angle_around_axis_rad <= -std::numbers::pi) out.angle_around_axis_rad = std::numbers::pi;
  return out;
}

}  // namespace microdex::knot
