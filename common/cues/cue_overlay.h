#pragma once
// The visual cues as data: polylines, colours and labels in world coordinates, computed from
// a station's state after a step, published on the CueOverlay topic (idl/cue_overlay.idl) at
// the mirror rate, so the station's own view and the instructor's mirror draw the same thing.
// A view draws each polyline as a line strip of its colour and width and each label as text
// at its point; it needs to know nothing about the cues. README.md in this folder gives the
// formulas and the colour scales.
//
// Fixed capacity, no allocation (the publisher thread calls it once per mirror period).

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "common/cues/cue_kind.h"
#include "common/cues/path_force_field.h"

namespace microdex::cues {

inline constexpr int kMaxOverlayPolylines = 8;
inline constexpr int kMaxOverlayPoints = 64;  // per polyline
inline constexpr int kMaxOverlayLabels = 4;
inline constexpr int kMaxOverlayLabelLength = 31;

// What a polyline or a label shows (the views may style by role; the colour is given anyway).
enum class OverlayRole : std::uint8_t {
  kPath = 0,        // visual_path: the ideal path
  kLimit = 1,       // visual_limits: the edges of the allowed band
  kDeviation = 2,   // visual_deviation: tool → nearest path point
  kClearance = 3,   // visual_clearance: tool (or needle point) → nearest wall point
  kPrediction = 4,  // predictive: tool → predicted end point
};

struct Rgba {
  float r = 1, g = 1, b = 1, a = 1;
};

struct OverlayPolyline {
  OverlayRole role = OverlayRole::kPath;
  Rgba colour;
  double width_m = 0;  // line width in world units (0: one pixel)
  int count = 0;
  std::array<Eigen::Vector3d, kMaxOverlayPoints> p_W;
};

struct OverlayLabel {
  OverlayRole role = OverlayRole::kPath;
  Rgba colour;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  std::array<char, kMaxOverlayLabelLength + 1> text{};  // NUL-terminated
};

struct CueOverlay {
  std::uint64_t step = 0;
  int polyline_count = 0;
  std::array<OverlayPolyline, kMaxOverlayPolylines> polylines;
  int label_count = 0;
  std::array<OverlayLabel, kMaxOverlayLabels> labels;
};

// The inputs: the cues switched on and their parameters, the task's path and tolerance, and
// the step's cue signals (state::CueState).
struct OverlayInput {
  std::uint64_t step = 0;
  std::uint32_t active = 0;
  std::array<double, kCueKindCount> param{};
  IdealPath path;
  double tolerance_m = 0;  // the task's tolerance (visual_limits / visual_deviation default)
  Eigen::Vector3d p_WT = Eigen::Vector3d::Zero();         // tool
  Eigen::Vector3d p_W_nearest = Eigen::Vector3d::Zero();  // nearest path point
  double deviation_m = 0;
  double clearance_m = 0;  // +inf: no wall in the scene
  bool has_wall_points = false;
  Eigen::Vector3d p_W_tool_near = Eigen::Vector3d::Zero();  // the tool's point nearest the wall
  Eigen::Vector3d p_W_wall = Eigen::Vector3d::Zero();       // the wall point nearest it
  bool prediction_valid = false;
  bool warning = false;
  Eigen::Vector3d p_W_end = Eigen::Vector3d::Zero();
  double prediction_error_m = 0;
};

// Green (x = 0) → yellow (0.5) → red (1); x clamped to [0, 1]; NaN gives grey.
Rgba CalcGradientColour(double x);

// The overlay of the cues that are on (empty when none is).
void CalcCueOverlay(const OverlayInput& in, CueOverlay& out);

}  // namespace microdex::cues
