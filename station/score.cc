#include "station/score.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace microdex::station {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Ratio(double num, double den) { return den > 0 ? num / den : kNaN; }

// The demos' formula (score.h, follow_path).
double CalcFollowPathScore(const scene::SceneModel& scene, const net::Score& s,
                           const state::ScoreState& t) {
  const double contact_fraction = std::clamp(t.time_in_contact_s / t.time_s, 0.0, 1.0);
  if (!scene.HasModule("needle")) return 100.0 * (1.0 - contact_fraction);
  if (t.clearance_samples == 0) return 0;
  const double g = std::clamp(s.mean_clearance_m / scene.vessel.tube_radius_m, 0.0, 1.0);
  return 100.0 * (1.0 - contact_fraction) * (1.0 + g) / 2.0;
}

}  // namespace

double CalcTaskPathLength(const scene::SceneModel& scene) {
  const scene::TaskDef& t = scene.task;
  if (t.kind == scene::TaskKind::kTremorHold) return 0;
  if (t.kind == scene::TaskKind::kGrasp) return 2 * (t.line_end_m - t.line_start_m).norm();
  if (t.kind == scene::TaskKind::kLoopAlongWire && scene.loop) {
    return scene.loop->wire.Length();
  }
  const double arc_radius_m =
      t.path == scene::PathKind::kCircle ? t.circle_radius_m : scene.needle.radius_m;
  const double one_pass = t.path == scene::PathKind::kLine
                              ? (t.line_end_m - t.line_start_m).norm()
                              : arc_radius_m * (t.end_azimuth_rad - t.start_azimuth_rad);
  return one_pass * t.passes;
}

double CalcScoreMetric(const scene::SceneModel& scene, const state::ScoreState& t,
                       const std::string& metric) {
  const auto samples = static_cast<double>(t.deviation_samples);
  if (metric == "time_s") return t.time_s;
  if (metric == "deviation_mean_m") return Ratio(t.deviation_sum_m, samples);
  if (metric == "deviation_max_m") return t.deviation_max_m;
  if (metric == "drift_m") return Ratio(t.drift_sum_m, samples);
  if (metric == "outside_fraction") return Ratio(t.time_outside_s, t.time_s);
  if (metric == "tremor_rms_m") {
    return std::sqrt(Ratio(t.tremor_sq_sum_m2, static_cast<double>(t.tremor_samples)));
  }
  if (metric == "contact_fraction") return Ratio(t.time_in_contact_s, t.time_s);
  if (metric == "contacts") return t.contacts;
  if (metric == "clearance_deficit") {
    const double mean = Ratio(t.clearance_sum_m, static_cast<double>(t.clearance_samples));
    return 1.0 - std::clamp(mean / scene.vessel.tube_radius_m, 0.0, 1.0);
  }
  if (metric == "excess_path") return Ratio(t.path_length_m, CalcTaskPathLength(scene)) - 1.0;
  if (metric == "object_rotation_rad") return t.object_rotation_rad;
  if (metric == "jaw_alignment_rad") return t.jaw_alignment_rad;
  if (metric == "object_drops") return t.object_drops;
  // Knot topology: unanswered knots count as wrong.
  if (metric == "wrong_fraction" && scene.knots) {
    const auto items = static_cast<double>(scene.knots->items.size());
    return (t.wrong_answers + (items - t.answers)) / items;
  }
  if (metric == "response_time_s") return Ratio(t.response_time_sum_s, t.answers);
  if (metric == "spacing_error_rad") return t.spacing_error_rad;
  if (metric == "bite_error_m") return t.bite_error_m;
  if (metric == "shape_error_m") return t.shape_error_m;
  // Knot tying: a square or surgeon's knot passes; any other (granny, slip, none) fails, as
  // does a knot not yet recognised or one whose stitch has torn out of the tissue.
  if (metric == "knot_wrong") {
    if (t.bite_pulled_out != 0) return 1.0;
    const auto square = static_cast<std::int32_t>(knot::StitchKnotType::kSquare);
    const auto surgeons = static_cast<std::int32_t>(knot::StitchKnotType::kSurgeons);
    return t.tied_knot == square || t.tied_knot == surgeons ? 0.0 : 1.0;
  }
  // Knot tying: the ends' pull in the hold against the hold tension (RMS, relative).
  if (metric == "tension_error") {
    return std::sqrt(Ratio(t.tension_sq_sum, static_cast<double>(t.tension_samples)));
  }
  if (metric == "entry_error_m") return t.entry_error_m;
  if (metric == "exit_error_m") return t.exit_error_m;
  if (metric == "peak_strain") return t.peak_strain;
  if (metric == "torn_m") return t.torn_m;
  if (metric == "off_circle_m") return t.off_circle_m;
  // Beyond the two the task needs (in and out).
  if (metric == "extra_punctures") return std::max(t.punctures - 2, 0);
  if (metric == "progress_deficit") {
    if (t.outcome == static_cast<std::uint8_t>(state::TaskOutcome::kCompleted)) return 0;
    const scene::TaskDef& task = scene.task;
    if (task.kind == scene::TaskKind::kTremorHold || task.kind == scene::TaskKind::kGrasp ||
        task.kind == scene::TaskKind::kLoopAlongWire ||
        task.kind == scene::TaskKind::kKnotTopology ||
        task.kind == scene::TaskKind::kKnotPlacement || task.kind == scene::TaskKind::kKnotTying) {
      return 1.0 - t.progress;
    }
    return 1.0 - (t.passes_done + t.progress) / task.passes;
  }
  return kNaN;
}

std::vector<Eigen::Vector3d> CalcStitchKnotPolyline(const scene::SceneModel& scene,
                                                    std::span<const Eigen::Vector3d> x_W) {
  if (!scene.knot_tying) return {};
  // The scene's frame (y up, the tissue the plane y = surface_y_m) to the recogniser's (the
  // tissue the plane z = 0, z out of it): a rotation about x and a shift.
  const double surface_y = scene.knot_tying->surface_y_m;
  std::vector<Eigen::Vector3d> p(x_W.size());
  for (std::size_t i = 0; i < x_W.size(); ++i) {
    p[i] = Eigen::Vector3d(x_W[i].x(), -x_W[i].z(), x_W[i].y() - surface_y);
  }
  // The tissue is where the stitch is: the run of nodes below the surface around the deepest
  // one (the bite). A tail that a hand's deviation took below the surface elsewhere lies on
  // the tissue, not through it: it is read as just above the surface.
  constexpr double kAbove_m = 1e-6;
  if (!p.empty()) {
    std::size_t deepest = 0;
    for (std::size_t i = 1; i < p.size(); ++i) {
      if (p[i].z() < p[deepest].z()) deepest = i;
    }
    std::size_t first = deepest, last = deepest;
    while (first > 0 && p[first - 1].z() < 0) --first;
    while (last + 1 < p.size() && p[last + 1].z() < 0) ++last;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if ((i < first || i > last) && p[i].z() < kAbove_m) p[i].z() = kAbove_m;
    }
  }
  return p;
}

knot::StitchKnotType RecogniseTiedKnot(const scene::SceneModel& scene,
                                       std::span<const Eigen::Vector3d> x_W) {
  if (!scene.knot_tying || !scene.thread) return knot::StitchKnotType::kUnknown;
  const std::vector<Eigen::Vector3d> p = CalcStitchKnotPolyline(scene, x_W);
  if (!knot::IsStitchPolyline(p)) return knot::StitchKnotType::kUnknown;
  knot::StitchKnotOptions options;
  options.thread_diameter_m = scene.thread->def.diameter_m;
  try {
    return knot::RecogniseStitchKnot(p, options);
  } catch (const std::invalid_argument&) {
    return knot::StitchKnotType::kUnknown;  // a degenerate polyline
  }
}

net::Score CalcScore(const scene::SceneModel& scene, const state::ScoreState& t) {
  net::Score s;
  s.duration_s = t.time_s;
  s.time_in_contact_s = t.time_in_contact_s;
  s.contacts = t.contacts;
  s.mean_clearance_m = Ratio(t.clearance_sum_m, static_cast<double>(t.clearance_samples));
  s.min_clearance_m = t.clearance_samples > 0 ? t.min_clearance_m : kNaN;
  s.path_length_m = t.path_length_m;
  s.ideal_path_length_m = t.ideal_path_length_m;
  s.tremor_rms_m = t.tremor_samples > 0
                       ? std::sqrt(t.tremor_sq_sum_m2 / static_cast<double>(t.tremor_samples))
                       : 0.0;
  s.task = scene::TaskKindName(scene.task.kind);
  s.outcome = t.outcome;
  s.deviation_mean_m = Ratio(t.deviation_sum_m, static_cast<double>(t.deviation_samples));
  s.progress = t.outcome == static_cast<std::uint8_t>(state::TaskOutcome::kCompleted)
                   ? 1.0
                   : 1.0 - CalcScoreMetric(scene, t, "progress_deficit");
  if (scene.task.kind == scene::TaskKind::kFollowPath) s.progress = 0;
  if (t.time_s <= 0) {
    s.score = 0;
    return s;
  }
  if (scene.task.kind == scene::TaskKind::kFollowPath) {
    s.score = CalcFollowPathScore(scene, s, t);
    return s;
  }
  double points = 0, weights = 0;
  for (const scene::ScoreTermDef& term : scene.scoring) {
    net::ScoreTerm out;
    out.metric = term.metric;
    out.value = CalcScoreMetric(scene, t, term.metric);
    out.limit = term.limit;
    out.weight = term.weight;
    // A metric without a value (no samples yet) earns nothing.
    out.points = std::isfinite(out.value)
                     ? term.weight * std::clamp(1.0 - out.value / term.limit, 0.0, 1.0)
                     : 0.0;
    points += out.points;
    weights += term.weight;
    s.terms.push_back(out);
  }
  s.score = weights > 0 ? 100.0 * points / weights : 0.0;
  return s;
}

}  // namespace microdex::station
