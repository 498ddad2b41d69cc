#pragma once
// Recognition of a surgical knot tied around a stitch (common/knot/README.md, "Knots tied
// around a stitch").
//
// The tissue is the plane z = 0. The thread enters the tissue, runs under it (its nodes with
// z < 0 are the stitch), comes out, and its two strands are tied above the surface; both ends
// are free. Two readings (README.md, "Tied throws and twisted pairs"):
// * A knot tied by passing ends through the loop closes, with the tails joined far outside,
//   to the knot the same throws make in a free thread (a reef knot to the square knot
//   3_1 # 3_1*): the closure names it, and the strands' twist only tells whether it capsized
//   into half hitches on one straight strand (slip, half hitch).
// * Strands only twisted about each other (a braid of two strands) close to the unknot; the
//   class is then read from the strands: they are matched along their length and the rotation
//   of the vector joining them about their common axis (the twist of the ribbon they span) is
//   followed from the tissue outwards. Each run of twisting in one sense is a throw, counted in
//   full turns and signed by its hand; a run in which one strand stays straight while the other
//   winds around it is a half hitch on that strand (the post).
//
// Handedness: a throw is right-handed (+1) when the two strands, both followed away from the
// tissue, twist about each other like a right-handed screw; every crossing between them in
// any projection of such a twist is then positive (the convention of recognition.h).

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/knot/recognition.h"

namespace microdex::knot {

enum class StitchKnotType {
  kNone,       // no throw: the strands leave the stitch without winding about each other
  kSquare,     // two single throws of opposite hands (reef knot)
  kGranny,     // two single throws of the same hand
  kSurgeons,   // a double throw, then a single throw of the opposite hand
  kSlip,       // two half hitches of one strand around the other, kept straight (the post)
  kHalfHitch,  // one half hitch: one strand wound once around the other, straight strand
  kUnknown,    // anything else (a lone throw, three throws, mixed throws and hitches, ...)
};

// The words of the `microdex-bench knot` contract for stitch knots: none, square, granny,
// surgeons, slip, half-hitch, unknown.
std::string_view StitchKnotName(StitchKnotType type);
// Inverse of StitchKnotName; nullopt for another word.
std::optional<StitchKnotType> StitchKnotTypeFromName(std::string_view name);

struct StitchKnotOptions {
  // Thread diameter; 0: the median link length (nodes about one diameter apart).
  double thread_diameter_m = 0.0;
  // The strands are twisting about each other only where they are closer than this many
  // diameters (beyond it they are the legs coming from the stitch or the tails).
  double contact_diameters = 4.0;
  // Half-width, in diameters, of the window that smooths the strands' common axis.
  double axis_window_diameters = 6.0;
  // A stretch of the strands is twisting where the twist changes by more than
  // `rate_threshold_turns` over `rate_window_diameters` of axis.
  double rate_window_diameters = 1.5;
  double rate_threshold_turns = 0.08;
  // Throws are separated by at least this much untwisted axis (diameters); shorter quiet
  // stretches (noise) do not end a run.
  double min_quiet_diameters = 1.5;
  // A reversal of the twist smaller than this (turns) does not end a run.
  double reversal_turns = 0.3;
  // A run of twisting counts as a throw or a hitch from this many turns on.
  double min_throw_turns = 0.6;
  // A run is a half hitch when the straighter strand over the run is nearly straight (chord
  // over arc length at least `post_straightness`: the post) and the shorter strand's length
  // is less than `hitch_length_ratio` of the longer one's (the other strand winds around
  // it). In a throw both strands wind about their common axis.
  double post_straightness = 0.85;
  double hitch_length_ratio = 0.75;
  // Also compute the evidence the class does not need: the Gauss linking integral of the two
  // strands (the closure's knot type is always computed: the class needs it).
  bool full_evidence = true;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

// A throw or half hitch found along the strands, in order from the tissue outwards.
struct StitchThrow {
  int hand = 0;               // +1 right-handed, -1 left-handed
  int turns = 0;              // full turns (1: single throw or hitch, 2: double throw)
  double twist_turns = 0.0;   // measured signed twist of the run
  bool hitch = false;         // one strand straight (the post), the other wound around it
  int post_strand = 0;        // hitch: 1 the strand of the first node, 2 of the last node
  double length_ratio = 0.0;  // shorter over longer strand length over the run
  // Chord over arc length of each strand over the run (1: straight): [0] the strand of the
  // first node, [1] of the last node.
  std::array<double, 2> straightness = {0.0, 0.0};
  double start_s_m = 0.0;  // along the strand of the first node, from its puncture
  double end_s_m = 0.0;
  Eigen::Vector3d p_center_W = Eigen::Vector3d::Zero();
};

struct StitchKnotAnalysis {
  StitchKnotType type = StitchKnotType::kUnknown;
  std::vector<StitchThrow> throws;
  // Why the class is unknown (empty otherwise).
  std::string reason;
  // Stitch: nodes [first_below, last_below] of the polyline are under the tissue; the
  // punctures are where the thread crosses z = 0 next to them.
  int first_below = -1;
  int last_below = -1;
  Eigen::Vector3d p_puncture_first_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_puncture_last_W = Eigen::Vector3d::Zero();
  double thread_diameter_m = 0.0;
  // Total twist of the two strands where they are in contact (turns; the sum of the runs and
  // of the partial turns between them).
  double total_twist_turns = 0.0;
  // Gauss linking integral of the two strands above the tissue, both oriented away from it:
  // a projection-free double integral, close to total_twist_turns when the strands' common
  // axis is nearly straight (Calugareanu-White: Lk = Tw + Wr). Full evidence only.
  double gauss_linking = 0.0;
  // Knot of the whole thread closed far outside (RecognizeKnot), always computed. A throw
  // tied by passing an end through the loop closes to a trefoil and a reef knot to the square
  // knot 3_1 # 3_1* (README.md, "Tied throws and twisted pairs"); strands only twisted about
  // each other close to the unknot.
  KnotType closure = KnotType::kUnknown;
  // The class was read from the closure (a tied knot), not from the twist of the strands.
  bool from_closure = false;
};

// Whether `polyline` is a thread through the tissue: its two end nodes above the surface
// (z > 0) and at least one node below (z < 0).
bool IsStitchPolyline(std::span<const Eigen::Vector3d> polyline);

// The knot tied around the stitch of `polyline` (node positions in world, metres, tissue at
// z = 0). Throws std::invalid_argument for fewer than 4 nodes, non-finite values, an end node
// not above the tissue, no node below it, or a strand with no node above the tissue.
StitchKnotAnalysis AnalyzeStitchKnot(std::span<const Eigen::Vector3d> polyline,
                                     const StitchKnotOptions& options = {});

// AnalyzeStitchKnot(...).type.
StitchKnotType RecogniseStitchKnot(std::span<const Eigen::Vector3d> polyline,
                                   const StitchKnotOptions& options = {});

// Gauss linking integral of two open polylines (exact for polygonal curves, summed over
// segment pairs): (1/4 pi) sum of the signed solid angles; an integer for closed curves.
double GaussLinkingIntegral(std::span<const Eigen::Vector3d> a, std::span<const Eigen::Vector3d> b);

}  // namespace microdex::knot
