#include "common/cues/cue_overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace microdex::cues {
namespace {

constexpr double kPi = 3.14159265358979323846;

OverlayPolyline* AddPolyline(CueOverlay& o, OverlayRole role, Rgba colour, double width_m) {
  if (o.polyline_count >= kMaxOverlayPolylines) return nullptr;
  OverlayPolyline& p = o.polylines[o.polyline_count++];
  p.role = role;
  p.colour = colour;
  p.width_m = width_m;
  p.count = 0;
  return &p;
}

void Push(OverlayPolyline* p, const Eigen::Vector3d& x) {
  if (p != nullptr && p->count < kMaxOverlayPoints) p->p_W[p->count++] = x;
}

void AddLabel(CueOverlay& o, OverlayRole role, Rgba colour, const Eigen::Vector3d& p_W,
              const char* fmt, double value) {
  if (o.label_count >= kMaxOverlayLabels) return;
  OverlayLabel& l = o.labels[o.label_count++];
  l.role = role;
  l.colour = colour;
  l.p_W = p_W;
  std::snprintf(l.text.data(), l.text.size(), fmt, value);
}

// The path as points: a segment's two ends, or the circle in kMaxOverlayPoints − 1 chords;
// `offset` moves each point along the in-plane normal (the circle: radially; the segment:
// along the normal in the xy-plane, z up being the microscope's axis).
void AddPathPoints(const IdealPath& path, double offset, OverlayPolyline* p) {
  if (path.is_segment) {
    const Eigen::Vector3d t = path.segment.b_W - path.segment.a_W;
    Eigen::Vector3d n = Eigen::Vector3d::UnitZ().cross(t);
    n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d(Eigen::Vector3d::UnitX());
    if (t.norm() == 0) {  // a hold target: a small circle of the offset around it
      for (int i = 0; i < kMaxOverlayPoints; ++i) {
        const double a = 2 * kPi * i / (kMaxOverlayPoints - 1);
        Push(p, path.segment.a_W + offset * Eigen::Vector3d(std::cos(a), std::sin(a), 0));
      }
      return;
    }
    Push(p, path.segment.a_W + offset * n);
    Push(p, path.segment.b_W + offset * n);
    return;
  }
  const double r = path.circle.radius_m + offset;
  for (int i = 0; i < kMaxOverlayPoints; ++i) {
    const double a = 2 * kPi * i / (kMaxOverlayPoints - 1);
    Push(p, path.circle.X_WC * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0));
  }
}

}  // namespace

Rgba CalcGradientColour(double x) {
  if (std::isnan(x)) return {0.5f, 0.5f, 0.5f, 1};
  x = std::clamp(x, 0.0, 1.0);
  // Green → yellow → red.
  const auto r = static_cast<float>(std::min(1.0, 2 * x));
  const auto g = static_cast<float>(std::min(1.0, 2 * (1 - x)));
  return {r, g, 0, 1};
}

void CalcCueOverlay(const OverlayInput& in, CueOverlay& out) {
  out.step = in.step;
  out.polyline_count = 0;
  out.label_count = 0;
  const auto on = [&](CueKind k) { return (in.active & CueBit(k)) != 0; };
  const auto param = [&](CueKind k) { return in.param[static_cast<std::size_t>(k)]; };
  const Rgba path_colour{0.2f, 0.6f, 1.0f, 0.8f};
  if (on(CueKind::kVisualPath)) {
    AddPathPoints(in.path, 0,
                  AddPolyline(out, OverlayRole::kPath, path_colour, param(CueKind::kVisualPath)));
  }
  if (on(CueKind::kVisualLimits)) {
    const double w =
        param(CueKind::kVisualLimits) > 0 ? param(CueKind::kVisualLimits) : in.tolerance_m;
    const Rgba c{1.0f, 0.6f, 0.1f, 0.6f};
    if (in.path.is_segment && (in.path.segment.b_W - in.path.segment.a_W).norm() == 0) {
      AddPathPoints(in.path, w, AddPolyline(out, OverlayRole::kLimit, c, 0));
    } else {
      AddPathPoints(in.path, w, AddPolyline(out, OverlayRole::kLimit, c, 0));
      AddPathPoints(in.path, -w, AddPolyline(out, OverlayRole::kLimit, c, 0));
    }
  }
  if (on(CueKind::kVisualDeviation)) {
    const double full =
        param(CueKind::kVisualDeviation) > 0 ? param(CueKind::kVisualDeviation) : in.tolerance_m;
    const Rgba c = CalcGradientColour(full > 0 ? in.deviation_m / full : 1.0);
    OverlayPolyline* p = AddPolyline(out, OverlayRole::kDeviation, c, 0);
    Push(p, in.p_WT);
    Push(p, in.p_W_nearest);
    AddLabel(out, OverlayRole::kDeviation, c, in.p_WT, "%.3f mm", in.deviation_m * 1e3);
  }
  if (on(CueKind::kVisualClearance) && std::isfinite(in.clearance_m)) {
    const double range = param(CueKind::kVisualClearance);
    const Rgba c = CalcGradientColour(1 - in.clearance_m / range);
    OverlayPolyline* p = AddPolyline(out, OverlayRole::kClearance, c, 0);
    Push(p, in.has_wall_points ? in.p_W_tool_near : in.p_WT);
    if (in.has_wall_points) Push(p, in.p_W_wall);
    AddLabel(out, OverlayRole::kClearance, c, in.has_wall_points ? in.p_W_tool_near : in.p_WT,
             "%.3f mm", in.clearance_m * 1e3);
  }
  if (on(CueKind::kPredictive) && in.prediction_valid) {
    const Rgba c = in.warning ? Rgba{1, 0, 0, 1} : Rgba{0.3f, 0.9f, 0.3f, 0.8f};
    OverlayPolyline* p = AddPolyline(out, OverlayRole::kPrediction, c, 0);
    Push(p, in.p_WT);
    Push(p, in.p_W_end);
    AddLabel(out, OverlayRole::kPrediction, c, in.p_W_end, in.warning ? "%.2f mm off" : "%.2f mm",
             in.prediction_error_m * 1e3);
  }
}

}  // namespace microdex::cues
