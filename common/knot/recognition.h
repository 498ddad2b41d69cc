#pragma once
// Knot recognition from the geometry of an open thread (thesis §2.2, knot-topology and
// knot-placement primitives).
//
// The open polyline is closed far outside its bounding ball, reduced by ambient-isotopy
// triangle moves, projected on generic directions, simplified by Reidemeister I/II moves and
// classified by exact invariants (Alexander polynomial, signature, Jones polynomial). See
// common/knot/README.md for the algorithm and the conventions.
//
// Chirality convention: "right" is the right-handed trefoil, the one whose reduced diagram
// has three positive crossings (writhe +3), signature -2 and Jones polynomial t + t^3 - t^4.
// A crossing is positive when, seen from the viewer, the over-strand direction turns
// counter-clockwise onto the under-strand direction (right-hand rule).

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "common/knot/laurent_polynomial.h"

namespace microdex::knot {

enum class KnotType {
  kNone,            // unknot
  kOverhandLeft,    // left-handed trefoil 3_1*
  kOverhandRight,   // right-handed trefoil 3_1
  kDoubleOverhand,  // cinquefoil 5_1 = T(2,5), the closed double overhand (either chirality)
  kFigureEight,     // 4_1 (amphichiral)
  kSquare,          // reef knot 3_1 # 3_1*
  kGranny,          // 3_1 # 3_1 or 3_1* # 3_1*
  kSurgeons,        // 5_1 # 3_1, the trefoil of the handedness opposite to the double throw
  kUnknown,         // anything else, or no consistent answer
};

// The words of the `microdex-bench knot` contract: none, overhand-left, overhand-right,
// double-overhand, figure-eight, square, granny, surgeons, unknown.
std::string_view KnotName(KnotType type);
// Inverse of KnotName; nullopt for a word that is not one of them.
std::optional<KnotType> KnotTypeFromName(std::string_view name);

struct KnotOptions {
  // Thread diameter, which scales the closure's clearance tests; 0: the median link length
  // (nodes about one diameter apart).
  double thread_diameter_m = 0.0;
  // Number of generic projection directions whose answers must agree (majority vote).
  int num_projections = 3;
  // Seed of the projection directions (deterministic results for a given polyline).
  std::uint64_t seed = 0x6b6e6f74;
  // Above this many crossings after simplification the Jones polynomial (a 2^n state sum) is
  // skipped and the class is decided by the Alexander polynomial and the signature alone.
  int max_jones_crossings = 16;
  // Reduce the closed polygon by triangle moves before projecting (false projects the whole
  // closed thread: slower, kept as the benchmark's baseline).
  bool reduce_polygon = true;
  // AnalyzeKnot: also find the knotted core along the thread (costs ~2 log2(n) extra
  // recognitions of sub-arcs).
  bool locate = true;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

struct KnotAnalysis {
  KnotType type = KnotType::kUnknown;
  // Vertices left after the isotopy reduction of the closed polygon.
  int reduced_vertices = 0;
  // Crossings of the projection of the reduced polygon, before and after Reidemeister I/II.
  int raw_crossings = 0;
  int crossings = 0;
  // Alexander polynomial in t, normalised to be symmetric (min_power = -max power) with a
  // positive leading coefficient. Unknot: {0, {1}}; trefoil: {-1, {1, -1, 1}}.
  LaurentPolynomial alexander;
  // |Alexander(-1)|; cross-checked against |det| of the Goeritz matrix.
  std::int64_t determinant = 1;
  // Knot signature (Gordon-Litherland); right-handed trefoil: -2.
  int signature = 0;
  // Jones polynomial in t (the knot's exponents are integers); empty coefficients when
  // skipped (see KnotOptions::max_jones_crossings). Right-handed trefoil: t + t^3 - t^4.
  LaurentPolynomial jones;
  bool jones_computed = false;
  // Projections whose invariants agreed with the reported ones, out of those tried.
  int projections_agreeing = 0;
  int projections_tried = 0;
  // Knotted core along the thread (KnotOptions::locate and a knot found): arc length from
  // the first node of the polyline, in metres, of the shortest sub-arc that still carries
  // the whole knot; the core's centre (arc-length weighted centroid of that sub-arc).
  bool located = false;
  double core_start_s_m = 0.0;
  double core_end_s_m = 0.0;
  Eigen::Vector3d p_core_W = Eigen::Vector3d::Zero();
};

// The knot type of the open thread `polyline` (node positions in world, metres; at least two
// distinct nodes, all finite — otherwise std::invalid_argument). Nodes are assumed spaced
// about one thread diameter apart; the result is invariant to rigid motions and scaling.
KnotType RecognizeKnot(std::span<const Eigen::Vector3d> polyline, const KnotOptions& = {});

// RecognizeKnot with the invariants, the crossing counts and the knotted core.
KnotAnalysis AnalyzeKnot(std::span<const Eigen::Vector3d> polyline, const KnotOptions& = {});

// Knot-placement target (thesis §2.2 knot-placement primitive): a vessel whose axis passes
// through p_axis_W along axis_W, angle zero along ref_W (projected normal to the axis), and
// the edge the knot should sit near as a polyline (one point is allowed).
struct KnotTargetDef {
  Eigen::Vector3d p_axis_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_W = Eigen::Vector3d::UnitX();
  Eigen::Vector3d ref_W = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> edge_W;
  // Throws std::invalid_argument naming the bad field (zero axis, ref parallel to the axis,
  // empty edge, non-finite values).
  void Validate() const;
};

struct KnotPlacement {
  // Knotted core along the thread (copied from the analysis) and its centre.
  double core_start_s_m = 0.0;
  double core_end_s_m = 0.0;
  double core_center_s_m = 0.0;
  Eigen::Vector3d p_core_W = Eigen::Vector3d::Zero();
  // Distance from the core centre to the edge polyline.
  double distance_to_edge_m = 0.0;
  // Angle of the core centre around the vessel axis from ref_W, right-handed about axis_W,
  // in (-pi, pi]; radial distance from the axis and position along it.
  double angle_around_axis_rad = 0.0;
  double radial_distance_m = 0.0;
  double axial_position_m = 0.0;
};

// Placement metrics of a located knot (analysis.located must be true, else
// std::invalid_argument).
KnotPlacement CalcKnotPlacement(const KnotAnalysis& analysis, const KnotTargetDef& target);

}  // namespace microdex::knot
