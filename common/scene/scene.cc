#include "common/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/base/yaml_reader.h"
#include "common/knot/obj.h"
#include "common/knot/stitch_knot_shapes.h"
#include "common/mesh/mesh_io.h"

namespace microdex::scene {
namespace {

constexpr double kTwoPi = 6.283185307179586;

// A Validate()-style error: "FIELD: reason".
[[noreturn]] void Invalid(const std::string& field, const std::string& what) {
  throw std::invalid_argument(field + ": " + what);
}

Eigen::Matrix3d RotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

PathKind ParsePathKind(const std::string& text) {
  if (text == "arc") return PathKind::kArc;
  if (text == "line") return PathKind::kLine;
  if (text == "circle") return PathKind::kCircle;
  throw std::invalid_argument("expected arc, line or circle");
}

TissueToolKind ParseToolKind(const std::string& text) {
  if (text == "point") return TissueToolKind::kPoint;
  if (text == "bar") return TissueToolKind::kBar;
  if (text == "needle") return TissueToolKind::kNeedle;
  throw std::invalid_argument("expected point, bar or needle");
}

cues::CueKind ParseCueName(const std::string& text) {
  cues::CueKind kind{};
  if (!cues::ParseCueKind(text, &kind) || kind == cues::CueKind::kClear) {
    throw std::invalid_argument("unknown cue '" + text + "' (known: " + cues::CueKindNames() + ")");
  }
  return kind;
}

// The metrics a scene's scoring may name (station/score.h defines them).
constexpr const char* kScoreMetrics[] = {"time_s",
                                         "deviation_mean_m",
                                         "deviation_max_m",
                                         "outside_fraction",
                                         "tremor_rms_m",
                                         "drift_m",
                                         "contact_fraction",
                                         "contacts",
                                         "clearance_deficit",
                                         "excess_path",
                                         "progress_deficit",
                                         "object_rotation_rad",
                                         "jaw_alignment_rad",
                                         "object_drops",
                                         "wrong_fraction",
                                         "response_time_s",
                                         "spacing_error_rad",
                                         "bite_error_m",
                                         "shape_error_m",
                                         "entry_error_m",
                                         "exit_error_m",
                                         "peak_strain",
                                         "torn_m",
                                         "off_circle_m",
                                         "extra_punctures",
                                         "knot_wrong",
                                         "tension_error"};

grasp::ShapeKind ParseGraspShape(const std::string& text) {
  for (grasp::ShapeKind k :
       {grasp::ShapeKind::kBox, grasp::ShapeKind::kCylinder, grasp::ShapeKind::kSphere}) {
    if (text == grasp::ShapeKindName(k)) return k;
  }
  throw std::invalid_argument("expected box, cylinder or sphere");
}

// One step of a wire course: "straight LENGTH_M" or "turn RADIUS_M ANGLE_RAD [PLANE_RAD]".
geometry::WireCourseStepDef ParseCourseStep(const std::string& text) {
  std::istringstream in(text);
  std::string kind;
  in >> kind;
  double a = 0, b = 0, c = 0;
  if (kind == "straight" && (in >> a) && (in >> std::ws).eof()) {
    if (!(a > 0) || !std::isfinite(a)) throw std::invalid_argument("expected a length > 0 m");
    return geometry::WireCourseStepDef::Straight(a);
  }
  if (kind == "turn" && (in >> a >> b)) {
    if (!(in >> std::ws).eof() && !(in >> c)) throw std::invalid_argument("bad turn plane");
    if (!(a > 0 && b > 0 && b <= 2 * 3.141592653589793) || !std::isfinite(c)) {
      throw std::invalid_argument("expected a radius > 0 m and an angle in (0, 2π]");
    }
    return geometry::WireCourseStepDef::Turn(a, b, c);
  }
  throw std::invalid_argument(
      "expected 'straight LENGTH_M' or 'turn RADIUS_M ANGLE_RAD [PLANE_RAD]'");
}

// A parameter file named in the scene: relative names are taken from the scene's folder.
std::string ResolveBeside(const std::string& origin, const std::string& name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return name;
  const std::filesystem::path dir = std::filesystem::path(origin).parent_path();
  return (dir / p).lexically_normal().string();
}

// Loads the parameter file named by section.params. A file that cannot be opened is the
// scene's error, at the line of params; any other error names the parameter file itself.
template <typename Def>
Def LoadParams(const YamlSection& section, const std::string& path,
               Def (*load)(const std::string&)) {
  try {
    return load(path);
  } catch (const InputError& e) {
    if (e.file() == path && e.line() <= 0) section.Fail("params", "cannot open file " + path);
    throw;
  }
}

// A mesh the scene names: loaded through assimp once at load, so a missing, unreadable or
// empty file is the scene's error at the field that names it (the views load it again).
void CheckMeshLoads(const YamlSection& visual, const std::string& path) {
  try {
    (void)mesh::LoadMesh(path);
  } catch (const InputError& e) {
    visual.Fail("mesh", e.what());
  }
}

SceneModel ReadScene(const YamlReader& reader) {
  const YamlSection root = reader.Root();
  root.CheckNoUnknownKeys({"name", "modules", "vessel", "needle", "task", "haptic", "thread",
                           "tissue", "puncture", "grasp", "loop", "knots", "placement",
                           "knot_tying", "scoring", "microscope", "visuals", "cues",
                           "second_hand"});
  SceneModel s;
  s.path = reader.file();
  s.name = root.String("name", "");
  root.Required("modules");
  s.modules = root.StringList("modules");
  if (const std::optional<YamlSection> v = root.OptionalMap("vessel")) {
    v->CheckNoUnknownKeys(
        {"core_radius_m", "tube_radius_m", "segment_angle_rad", "position_m", "rpy_rad"});
    s.vessel.core_radius_m = v->FiniteDouble("core_radius_m", s.vessel.core_radius_m);
    s.vessel.tube_radius_m = v->FiniteDouble("tube_radius_m", s.vessel.tube_radius_m);
    s.vessel.segment_angle_rad = v->FiniteDouble("segment_angle_rad", s.vessel.segment_angle_rad);
    const Eigen::Vector3d p = v->Vec3("position_m", Eigen::Vector3d::Zero());
    const Eigen::Vector3d rpy = v->Vec3("rpy_rad", Eigen::Vector3d::Zero());
    s.vessel.X_WV = Eigen::Isometry3d::Identity();
    s.vessel.X_WV.translate(p);
    s.vessel.X_WV.rotate(RotationFromRpy(rpy));
  }
  if (const std::optional<YamlSection> n = root.OptionalMap("needle")) {
    n->CheckNoUnknownKeys({"radius_m", "sweep_rad"});
    s.needle.radius_m = n->FiniteDouble("radius_m", s.needle.radius_m);
    s.needle.sweep_rad = n->FiniteDouble("sweep_rad", s.needle.sweep_rad);
  }
  if (const std::optional<YamlSection> t = root.OptionalMap("task")) {
    t->CheckNoUnknownKeys({"kind", "passes", "time_limit_s", "tolerance_m", "target_m", "hold_s",
                           "pass_duration_s", "start_azimuth_rad", "end_azimuth_rad", "path",
                           "circle_center_m", "circle_radius_m", "line_start_m", "line_end_m",
                           "tool_rpy_rad"});
    s.task.kind = t->Enum("kind", &ParseTaskKind, TaskKind::kFollowPath);
    s.task.passes = t->Int("passes", s.task.passes);
    s.task.time_limit_s = t->FiniteDouble("time_limit_s", s.task.time_limit_s);
    s.task.tolerance_m = t->FiniteDouble("tolerance_m", s.task.tolerance_m);
    s.task.target_m = t->Vec3("target_m", s.task.target_m);
    s.task.hold_s = t->FiniteDouble("hold_s", s.task.hold_s);
    s.task.path = t->Enum("path", &ParsePathKind, PathKind::kArc);
    s.task.circle_center_m = t->Vec3("circle_center_m", s.task.circle_center_m);
    s.task.circle_radius_m = t->FiniteDouble("circle_radius_m", s.task.circle_radius_m);
    s.task.line_start_m = t->Vec3("line_start_m", s.task.line_start_m);
    s.task.line_end_m = t->Vec3("line_end_m", s.task.line_end_m);
    s.task.R_WT_line = RotationFromRpy(t->Vec3("tool_rpy_rad", Eigen::Vector3d::Zero()));
    s.task.pass_duration_s = t->FiniteDouble("pass_duration_s", s.task.pass_duration_s);
    s.task.start_azimuth_rad = t->FiniteDouble("start_azimuth_rad", s.task.start_azimuth_rad);
    s.task.end_azimuth_rad = t->FiniteDouble("end_azimuth_rad", s.task.end_azimuth_rad);
  }
  if (const std::optional<YamlSection> h = root.OptionalMap("haptic")) {
    h->CheckNoUnknownKeys({"rate_hz", "max_force_N", "max_torque_Nm", "wall_stiffness_N_per_m"});
    s.haptic.rate_hz = h->FiniteDouble("rate_hz", s.haptic.rate_hz);
    s.haptic.max_force_N = h->FiniteDouble("max_force_N", s.haptic.max_force_N);
    s.haptic.max_torque_Nm = h->FiniteDouble("max_torque_Nm", s.haptic.max_torque_Nm);
    s.haptic.wall_stiffness_N_per_m =
        h->FiniteDouble("wall_stiffness_N_per_m", s.haptic.wall_stiffness_N_per_m);
  }
  if (const std::optional<YamlSection> th = root.OptionalMap("thread")) {
    th->CheckNoUnknownKeys({"params", "anchor_m", "slack_side", "floor_height_m", "max_strain"});
    ThreadSceneDef d;
    th->Required("params");
    const std::string params = th->String("params", "");
    if (params.empty()) th->Fail("params", "expected a thread parameter file");
    d.params_path = ResolveBeside(s.path, params);
    d.def = LoadParams(*th, d.params_path, &thread::LoadThreadDef);
    // The thread steps once per haptic tick.
    d.def.time_step_s = 1.0 / s.haptic.rate_hz;
    d.p_W_anchor = th->Vec3("anchor_m", Eigen::Vector3d::Zero());
    if (th->Has("slack_side")) {
      const Eigen::Vector3d side = th->Vec3("slack_side", Eigen::Vector3d::Zero());
      d.slack_side_W = side.norm() > 0 ? Eigen::Vector3d(side.normalized()) : side;
    }
    d.floor_height_m = th->FiniteDouble("floor_height_m", d.floor_height_m);
    d.max_strain = th->FiniteDouble("max_strain", d.max_strain);
    s.thread = d;
  }
  if (const std::optional<YamlSection> ti = root.OptionalMap("tissue")) {
    ti->CheckNoUnknownKeys({"params", "position_m", "rpy_rad", "tool", "contact_radius_m",
                            "bar_length_m", "display_level", "max_force_N", "level", "max_level",
                            "solver", "grading", "cg_relative_tolerance", "cg_max_iterations"});
    TissueSceneDef d;
    ti->Required("params");
    const std::string params = ti->String("params", "");
    if (params.empty()) ti->Fail("params", "expected a tissue parameter file");
    d.params_path = ResolveBeside(s.path, params);
    d.def = LoadParams(*ti, d.params_path, &fem::LoadTissueDef);
    // The scene's overrides of the parameter file (a station picks the level and solver that
    // fit its haptic period).
    d.def.level = ti->Int("level", d.def.level);
    d.def.max_level = ti->Int("max_level", d.def.max_level);
    d.def.grading = ti->FiniteDouble("grading", d.def.grading);
    d.def.cg_relative_tolerance =
        ti->FiniteDouble("cg_relative_tolerance", d.def.cg_relative_tolerance);
    d.def.cg_max_iterations = ti->Int("cg_max_iterations", d.def.cg_max_iterations);
    d.def.solver = ti->Enum("solver", &fem::ParseSolverKind, d.def.solver);
    const Eigen::Vector3d p = ti->Vec3("position_m", Eigen::Vector3d::Zero());
    d.X_WS = Eigen::Isometry3d::Identity();
    d.X_WS.translate(p);
    d.X_WS.rotate(RotationFromRpy(ti->Vec3("rpy_rad", Eigen::Vector3d::Zero())));
    d.tool = ti->Enum("tool", &ParseToolKind, TissueToolKind::kPoint);
    d.contact_radius_m = ti->FiniteDouble("contact_radius_m", d.contact_radius_m);
    d.bar_length_m = ti->FiniteDouble("bar_length_m", d.bar_length_m);
    d.display_level = ti->Int("display_level", d.display_level);
    d.max_force_N = ti->FiniteDouble("max_force_N", d.max_force_N);
    s.tissue = d;
  }
  if (const std::optional<YamlSection> pu = root.OptionalMap("puncture")) {
    pu->CheckNoUnknownKeys({"puncture_force_N", "wire_radius_m", "lateral_stiffness_N_per_m",
                            "tear_strain", "grip_force_N", "friction_coefficient",
                            "bristle_stiffness_N_per_m", "entry_target_m", "exit_target_m"});
    PunctureSceneDef d;
    puncture::PunctureDef& p = d.def;
    p.puncture_force_N = pu->FiniteDouble("puncture_force_N", p.puncture_force_N);
    p.wire_radius_m = pu->FiniteDouble("wire_radius_m", p.wire_radius_m);
    p.lateral_stiffness_N_per_m =
        pu->FiniteDouble("lateral_stiffness_N_per_m", p.lateral_stiffness_N_per_m);
    p.tear_strain = pu->FiniteDouble("tear_strain", p.tear_strain);
    p.grip_force_N = pu->FiniteDouble("grip_force_N", p.grip_force_N);
    p.friction_coefficient = pu->FiniteDouble("friction_coefficient", p.friction_coefficient);
    p.bristle_stiffness_N_per_m =
        pu->FiniteDouble("bristle_stiffness_N_per_m", p.bristle_stiffness_N_per_m);
    pu->Required("entry_target_m");
    pu->Required("exit_target_m");
    d.p_W_entry_target = pu->Vec3("entry_target_m", d.p_W_entry_target);
    d.p_W_exit_target = pu->Vec3("exit_target_m", d.p_W_exit_target);
    s.puncture = d;
  }
  if (const std::optional<YamlSection> g = root.OptionalMap("grasp")) {
    g->CheckNoUnknownKeys({"shape", "size_m", "radius_m", "length_m", "density_kg_per_m3",
                           "friction", "position_m", "yaw_rad", "lift_height_m",
                           "jaw_stiffness_N_per_m", "jaw_open_gap_m", "jaw_closed_gap_m"});
    GraspSceneDef d;
    d.def.shape.kind = g->Enum("shape", &ParseGraspShape, d.def.shape.kind);
    d.def.shape.box_size_m = g->Vec3("size_m", d.def.shape.box_size_m);
    d.def.shape.radius_m = g->FiniteDouble("radius_m", d.def.shape.radius_m);
    d.def.shape.length_m = g->FiniteDouble("length_m", d.def.shape.length_m);
    d.def.density_kg_per_m3 = g->FiniteDouble("density_kg_per_m3", d.def.density_kg_per_m3);
    d.def.jaw_friction = d.def.table_friction = g->FiniteDouble("friction", d.def.jaw_friction);
    d.def.contact.jaw_stiffness_N_per_m =
        g->FiniteDouble("jaw_stiffness_N_per_m", d.def.contact.jaw_stiffness_N_per_m);
    d.def.jaws.open_gap_m = g->FiniteDouble("jaw_open_gap_m", d.def.jaws.open_gap_m);
    d.def.jaws.closed_gap_m = g->FiniteDouble("jaw_closed_gap_m", d.def.jaws.closed_gap_m);
    d.p_W_object = g->Vec3("position_m", d.p_W_object);
    d.yaw_rad = g->FiniteDouble("yaw_rad", d.yaw_rad);
    d.lift_height_m = g->FiniteDouble("lift_height_m", d.lift_height_m);
    s.grasp = d;
  }
  if (const std::optional<YamlSection> l = root.OptionalMap("loop")) {
    l->CheckNoUnknownKeys({"radius_m", "wire_radius_m", "course", "wall_stiffness_N_per_m"});
    LoopSceneDef d;
    d.loop.radius_m = l->FiniteDouble("radius_m", d.loop.radius_m);
    d.loop.wire_radius_m = l->FiniteDouble("wire_radius_m", d.loop.wire_radius_m);
    d.wall_stiffness_N_per_m = l->FiniteDouble("wall_stiffness_N_per_m", d.wall_stiffness_N_per_m);
    const YamlSection c = l->Map("course");
    c.CheckNoUnknownKeys({"position_m", "rpy_rad", "wire_radius_m", "steps"});
    Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();
    X_WS.translate(c.Vec3("position_m", Eigen::Vector3d::Zero()));
    X_WS.rotate(RotationFromRpy(c.Vec3("rpy_rad", Eigen::Vector3d::Zero())));
    c.Required("steps");
    std::vector<geometry::WireCourseStepDef> steps;
    for (const std::string& text : c.StringList("steps")) {
      try {
        steps.push_back(ParseCourseStep(text));
      } catch (const std::invalid_argument& e) {
        c.Fail("steps", "'" + text + "': " + e.what());
      }
    }
    const double wire_radius_m = c.FiniteDouble("wire_radius_m", d.wire.radius_m);
    try {
      d.wire = geometry::MakeWireCourse(X_WS, steps, wire_radius_m);
    } catch (const std::invalid_argument& e) {
      c.Fail("steps", e.what());
    }
    s.loop = d;
  }
  if (const std::optional<YamlSection> k = root.OptionalMap("knots")) {
    k->CheckNoUnknownKeys({"items", "thread_diameter_m", "tied"});
    KnotQuizSceneDef d;
    k->Required("items");
    for (const std::string& name : k->StringList("items")) {
      const std::optional<knot::StitchKnotType> type = knot::StitchKnotTypeFromName(name);
      if (!type || *type == knot::StitchKnotType::kNone ||
          *type == knot::StitchKnotType::kUnknown) {
        k->Fail("items", "'" + name + "': expected square, granny, surgeons, slip or half-hitch");
      }
      d.items.push_back(*type);
    }
    d.thread_diameter_m = k->FiniteDouble("thread_diameter_m", d.thread_diameter_m);
    if (const std::optional<YamlSection> tied = k->OptionalMap("tied")) {
      // The tails are shown up to this far from the stitch (the knot and the stitch, not the
      // whole suture); the knot (knot::CalcStitchKnotCore: its throws' wraps and crossings, a
      // tenth of a millimetre across, the throws up to 3.5 mm apart) is centred over the origin
      // in x and y and drawn kTiedSpan_m across (the field of a 20x microscope is 10 mm high,
      // 18 mm wide), at 2.5 to 10 times its size. Moving and scaling keep the topology: the
      // recogniser checks each one below.
      constexpr double kTiedRadius_m = 5e-3;
      constexpr double kTiedSpan_m = 8e-3;
      constexpr double kTiedMinScale = 2.5, kTiedMaxScale = 10.0;
      tied->CheckNoUnknownKeys({"square", "granny", "surgeons", "slip", "half-hitch"});
      for (const char* name : {"square", "granny", "surgeons", "slip", "half-hitch"}) {
        if (!tied->Has(name)) continue;
        const std::string file = ResolveBeside(s.path, tied->String(name, ""));
        double diameter_m = 0.0;
        try {
          std::vector<Eigen::Vector3d> shape =
              knot::CropStitchTails(knot::ReadObjPolyline(file, &diameter_m), kTiedRadius_m);
          Eigen::AlignedBox3d box = knot::CalcStitchKnotCore(shape, diameter_m);
          if (box.isEmpty()) {  // no strands in contact: the whole thread
            for (const Eigen::Vector3d& p : shape) box.extend(p);
          }
          const Eigen::Vector3d centre(box.center().x(), box.center().y(), 0.0);
          const double span_m = std::max(box.sizes().x(), box.sizes().y());
          const double scale =
              std::clamp(kTiedSpan_m / std::max(span_m, 1e-9), kTiedMinScale, kTiedMaxScale);
          for (Eigen::Vector3d& p : shape) p = scale * (p - centre);
          d.tied.push_back(
              {*knot::StitchKnotTypeFromName(name), std::move(shape), scale * diameter_m});
        } catch (const std::exception& e) {
          tied->Fail(name, e.what());
        }
        knot::StitchKnotOptions options;
        options.thread_diameter_m = d.tied.back().thread_diameter_m;
        const knot::StitchKnotType seen = knot::RecogniseStitchKnot(d.tied.back().shape, options);
        if (seen != d.tied.back().type) {
          tied->Fail(name, file + ": recognised as " + std::string(knot::StitchKnotName(seen)));
        }
      }
    }
    // Every item shown is the knot it asks for: the parametric ones (each item its own shape)
    // and the tied ones drawn mirrored (every second item of a class; the tied shape itself was
    // checked above, naming its file).
    for (std::size_t i = 0; i < d.items.size(); ++i) {
      const auto tied = std::find_if(d.tied.begin(), d.tied.end(),
                                     [&](const auto& t) { return t.type == d.items[i]; });
      const auto before =
          std::count(d.items.begin(), d.items.begin() + static_cast<std::ptrdiff_t>(i), d.items[i]);
      if (tied != d.tied.end() && before != 1) continue;  // the same shape as one checked
      knot::StitchKnotOptions options;
      options.thread_diameter_m = d.ItemThreadDiameter(i);
      const knot::StitchKnotType seen = knot::RecogniseStitchKnot(d.ItemShape(i), options);
      if (seen != d.items[i]) {
        k->Fail("items", "[" + std::to_string(i) + "]: the " +
                             std::string(knot::StitchKnotName(d.items[i])) +
                             " knot shown would be recognised as " +
                             std::string(knot::StitchKnotName(seen)));
      }
    }
    s.knots = d;
  }
  if (const std::optional<YamlSection> pl = root.OptionalMap("placement")) {
    pl->CheckNoUnknownKeys({"vessel_radius_m", "end_height_m", "stitches", "bite_m", "move_s"});
    PlacementSceneDef d;
    d.vessel_radius_m = pl->FiniteDouble("vessel_radius_m", d.vessel_radius_m);
    d.end_height_m = pl->FiniteDouble("end_height_m", d.end_height_m);
    d.stitches = pl->Int("stitches", d.stitches);
    d.bite_m = pl->FiniteDouble("bite_m", d.bite_m);
    d.move_s = pl->FiniteDouble("move_s", d.move_s);
    s.placement = d;
  }
  if (const std::optional<YamlSection> kt = root.OptionalMap("knot_tying")) {
    kt->CheckNoUnknownKeys({"stitch", "throws", "speed_m_per_s", "pull_tension_N",
                            "force_limited_pull", "throw_tension_N", "hold_tension_N", "hold_s",
                            "first_jig_x_m", "next_jig_x_m", "surface_y_m", "stitch_relax_s",
                            "bite_tear_N", "hold_pull_N_per_m", "stitch_in_plane"});
    KnotTyingSceneDef d;
    if (const std::optional<YamlSection> st = kt->OptionalMap("stitch")) {
      st->CheckNoUnknownKeys(
          {"x_m", "depth_m", "guide_offset_m", "rod_radius_m", "guide_radius_m", "start_x_m"});
      thread::KnotStitchDef& k = d.stitch;
      k.x_m = st->FiniteDouble("x_m", k.x_m);
      k.depth_m = st->FiniteDouble("depth_m", k.depth_m);
      k.guide_offset_m = st->FiniteDouble("guide_offset_m", k.guide_offset_m);
      k.rod_radius_m = st->FiniteDouble("rod_radius_m", k.rod_radius_m);
      k.guide_radius_m = st->FiniteDouble("guide_radius_m", k.guide_radius_m);
      k.start_x_m = st->FiniteDouble("start_x_m", k.start_x_m);
      try {
        k.Validate();
      } catch (const std::invalid_argument& e) {
        st->FailInvalid(e);
      }
    }
    d.throws = kt->Int("throws", d.throws);
    d.speed_m_per_s = kt->FiniteDouble("speed_m_per_s", d.speed_m_per_s);
    d.pull_tension_N = kt->FiniteDouble("pull_tension_N", d.pull_tension_N);
    d.force_limited_pull = kt->Bool("force_limited_pull", d.force_limited_pull);
    d.throw_tension_N = kt->FiniteDouble("throw_tension_N", d.throw_tension_N);
    d.hold_tension_N = kt->FiniteDouble("hold_tension_N", d.hold_tension_N);
    d.hold_s = kt->FiniteDouble("hold_s", d.hold_s);
    d.hold_pull_N_per_m = kt->FiniteDouble("hold_pull_N_per_m", d.hold_pull_N_per_m);
    d.first_jig_x_m = kt->FiniteDouble("first_jig_x_m", d.first_jig_x_m);
    d.next_jig_x_m = kt->FiniteDouble("next_jig_x_m", d.next_jig_x_m);
    d.surface_y_m = kt->FiniteDouble("surface_y_m", d.surface_y_m);
    d.stitch_relax_s = kt->FiniteDouble("stitch_relax_s", d.stitch_relax_s);
    d.bite_tear_N = kt->FiniteDouble("bite_tear_N", d.bite_tear_N);
    d.stitch_in_plane = kt->Bool("stitch_in_plane", d.stitch_in_plane);
    s.knot_tying = d;
  }
  if (const std::optional<YamlSection> sc = root.OptionalMap("scoring")) {
    std::vector<std::string_view> known(std::begin(kScoreMetrics), std::end(kScoreMetrics));
    for (const char* metric : kScoreMetrics) {
      const std::optional<YamlSection> term = sc->OptionalMap(metric);
      if (!term) continue;
      term->CheckNoUnknownKeys({"weight", "limit"});
      term->Required("limit");
      s.scoring.push_back(
          {metric, term->FiniteDouble("weight", 1.0), term->FiniteDouble("limit", 1.0)});
    }
    sc->CheckNoUnknownKeys(known);
  }
  if (const std::optional<YamlSection> h = root.OptionalMap("second_hand")) {
    h->CheckNoUnknownKeys({"position_m", "rpy_rad"});
    h->Required("position_m");
    SecondHandDef d;
    d.X_WT_start.translate(h->Vec3("position_m", Eigen::Vector3d::Zero()));
    d.X_WT_start.rotate(RotationFromRpy(h->Vec3("rpy_rad", Eigen::Vector3d::Zero())));
    s.second_hand = d;
  }
  if (const std::optional<YamlSection> m = root.OptionalMap("microscope")) {
    m->CheckNoUnknownKeys({"magnification", "look_at_m", "view_dir"});
    s.microscope.magnification = m->FiniteDouble("magnification", s.microscope.magnification);
    s.microscope.look_at_m = m->Vec3("look_at_m", s.microscope.look_at_m);
    const Eigen::Vector3d dir = m->Vec3("view_dir", s.microscope.view_dir_W);
    if (!(dir.norm() > 0)) m->Fail("view_dir", "expected a non-zero vector");
    s.microscope.view_dir_W = dir.normalized();
  }
  if (const std::optional<YamlSection> vs = root.OptionalMap("visuals")) {
    std::vector<std::string_view> known(std::begin(kVisualRoles), std::end(kVisualRoles));
    for (const char* role : kVisualRoles) {
      const std::optional<YamlSection> v = vs->OptionalMap(role);
      if (!v) continue;
      v->CheckNoUnknownKeys({"mesh", "position_m", "rpy_rad"});
      v->Required("mesh");
      VisualDef d;
      d.role = role;
      d.mesh_path = ResolveBeside(s.path, v->String("mesh", ""));
      CheckMeshLoads(*v, d.mesh_path);
      d.X_PM.translate(v->Vec3("position_m", Eigen::Vector3d::Zero()));
      d.X_PM.rotate(RotationFromRpy(v->Vec3("rpy_rad", Eigen::Vector3d::Zero())));
      s.visuals.push_back(d);
    }
    vs->CheckNoUnknownKeys(known);
  }
  if (const std::optional<YamlSection> c = root.OptionalMap("cues")) {
    c->CheckNoUnknownKeys({"available", "on"});
    if (c->Has("available")) {
      for (const std::string& name : c->StringList("available")) {
        try {
          s.cues.available.push_back(ParseCueName(name));
        } catch (const std::invalid_argument& e) {
          c->Fail("available", e.what());
        }
      }
    }
    if (const std::optional<YamlSection> on = c->OptionalMap("on")) {
      // Every kind but clear, by its name ("tremor": the first release's name of
      // amplified_tremor).
      std::vector<std::string> names = {"tremor"};
      for (std::uint32_t k = 1; k < cues::kCueKindCount; ++k) {
        names.emplace_back(cues::CueKindName(static_cast<cues::CueKind>(k)));
      }
      const std::vector<std::string_view> keys(names.begin(), names.end());
      on->CheckNoUnknownKeys(keys);
      for (const std::string& name : names) {
        if (on->Has(name.c_str())) {
          s.cues.on.emplace_back(ParseCueName(name), on->FiniteDouble(name.c_str(), 0));
        }
      }
    }
  }
  try {
    ValidateScene(s);
  } catch (const std::invalid_argument& e) {
    root.FailInvalid(e);
  }
  s.needle.X_WN = s.CalcIdealX_WT(s.task.start_azimuth_rad) * s.X_TN();
  return s;
}

}  // namespace

const char* TaskKindName(TaskKind kind) {
  switch (kind) {
    case TaskKind::kFollowPath:
      return "follow_path";
    case TaskKind::kTremorHold:
      return "tremor_hold";
    case TaskKind::kNeedleAlongTube:
      return "needle_along_tube";
    case TaskKind::kGrasp:
      return "grasp";
    case TaskKind::kLoopAlongWire:
      return "loop_along_wire";
    case TaskKind::kKnotTopology:
      return "knot_topology";
    case TaskKind::kKnotPlacement:
      return "knot_placement";
    case TaskKind::kNylonLoop:
      return "nylon_loop";
    case TaskKind::kNeedleThroughTissue:
      return "needle_through_tissue";
    case TaskKind::kKnotTying:
      return "knot_tying";
  }
  return "unknown";
}

TaskKind ParseTaskKind(const std::string& text) {
  for (TaskKind k :
       {TaskKind::kFollowPath, TaskKind::kTremorHold, TaskKind::kNeedleAlongTube, TaskKind::kGrasp,
        TaskKind::kLoopAlongWire, TaskKind::kKnotTopology, TaskKind::kKnotPlacement,
        TaskKind::kNylonLoop, TaskKind::kNeedleThroughTissue, TaskKind::kKnotTying}) {
    if (text == TaskKindName(k)) return k;
  }
  throw std::invalid_argument(
      "expected follow_path, tremor_hold, needle_along_tube, grasp, loop_along_wire, "
      "knot_topology, knot_placement, nylon_loop, needle_through_tissue or knot_tying");
}

std::vector<Eigen::Vector3d> KnotQuizSceneDef::ItemShape(std::size_t i) const {
  const knot::StitchKnotType type = items.at(i);
  for (const TiedKnot& t : tied) {
    if (t.type != type) continue;
    const auto before =
        std::count(items.begin(), items.begin() + static_cast<std::ptrdiff_t>(i), type);
    std::vector<Eigen::Vector3d> out = t.shape;
    if (before % 2 == 1) {
      for (Eigen::Vector3d& p : out) p.x() = -p.x();
    }
    return out;
  }
  return knot::MakeStitchKnot(knot::QuizItemShapeDef(type, i, thread_diameter_m));
}

double KnotQuizSceneDef::ItemThreadDiameter(std::size_t i) const {
  const knot::StitchKnotType type = items.at(i);
  for (const TiedKnot& t : tied) {
    if (t.type == type) return t.thread_diameter_m;
  }
  return thread_diameter_m;
}

Eigen::Isometry3d CalcWireCoursePose(const geometry::WireDef& wire, double fraction) {
  const double total = wire.Length();
  double s = std::clamp(fraction, 0.0, 1.0) * total;
  Eigen::Vector3d p_W = wire.pieces.back().EndPoint(), t_W = Eigen::Vector3d::UnitX();
  for (const geometry::WirePieceDef& p : wire.pieces) {
    const double length = p.Length();
    if (s > length && &p != &wire.pieces.back()) {
      s -= length;
      continue;
    }
    const double u = std::min(s / length, 1.0);
    if (p.kind == geometry::WirePieceDef::Kind::kSegment) {
      p_W = p.p_W0 + u * (p.p_W1 - p.p_W0);
      t_W = (p.p_W1 - p.p_W0).normalized();
    } else {
      const double angle = u * p.sweep_rad;
      const Eigen::Vector3d v_W = p.axis_W.cross(p.u_W);
      const Eigen::Vector3d radial = std::cos(angle) * p.u_W + std::sin(angle) * v_W;
      p_W = p.p_WO + p.radius_m * radial;
      t_W = p.axis_W.cross(radial).normalized();
    }
    break;
  }
  // The loop's plane across the wire: z_T along the tangent.
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), t_W).toRotationMatrix();
  X.translation() = p_W;
  return X;
}

bool SceneModel::HasModule(const std::string& module) const {
  return std::find(modules.begin(), modules.end(), module) != modules.end();
}

Eigen::Isometry3d SceneModel::CalcIdealX_WT(double theta_rad) const {
  Eigen::Isometry3d X_VT = Eigen::Isometry3d::Identity();
  X_VT.rotate(Eigen::AngleAxisd(theta_rad, Eigen::Vector3d::UnitZ()));
  X_VT.translate(Eigen::Vector3d(needle.radius_m, 0, 0));
  return vessel.X_WV * X_VT;
}

double SceneModel::CalcIdealAzimuth(double t_s) const {
  const double T = task.pass_duration_s;
  const double passes = std::floor(t_s / T);
  const double tau = t_s / T - passes;
  const double shape = tau * tau * tau * (10 + tau * (-15 + 6 * tau));
  const bool forward = std::fmod(passes, 2.0) == 0.0;
  const double a = forward ? task.start_azimuth_rad : task.end_azimuth_rad;
  const double b = forward ? task.end_azimuth_rad : task.start_azimuth_rad;
  return a + (b - a) * shape;
}

double SceneModel::CalcIdealPathFraction(double t_s) const {
  const double T = task.pass_duration_s;
  const double passes = std::floor(t_s / T);
  const double tau = t_s / T - passes;
  const double shape = tau * tau * tau * (10 + tau * (-15 + 6 * tau));
  return std::fmod(passes, 2.0) == 0.0 ? shape : 1.0 - shape;
}

Eigen::Isometry3d SceneModel::CalcIdealToolPose(double t_s) const {
  if (task.kind == TaskKind::kLoopAlongWire && loop) {
    return CalcWireCoursePose(loop->wire, CalcIdealPathFraction(t_s));
  }
  if (task.kind == TaskKind::kTremorHold || task.kind == TaskKind::kKnotTying) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = task.R_WT_line;
    X.translation() = task.target_m;
    return X;
  }
  if (task.path == PathKind::kArc) return CalcIdealX_WT(CalcIdealAzimuth(t_s));
  if (task.path == PathKind::kCircle) {
    const double theta = CalcIdealAzimuth(t_s);
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = task.R_WT_line;
    X.translation() = task.circle_center_m +
                      task.circle_radius_m * Eigen::Vector3d(std::cos(theta), std::sin(theta), 0);
    return X;
  }
  const double u = CalcIdealPathFraction(t_s);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = task.R_WT_line;
  X.translation() = task.line_start_m + u * (task.line_end_m - task.line_start_m);
  return X;
}

Eigen::Isometry3d SceneModel::CalcIdealSecondToolPose(double /*t_s*/) const {
  return second_hand ? second_hand->X_WT_start : Eigen::Isometry3d::Identity();
}

Eigen::Isometry3d SceneModel::X_TN() const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translate(Eigen::Vector3d(-needle.radius_m, 0, 0));
  return X;
}

void ValidateScene(const SceneModel& s) {
  if (s.name.empty()) Invalid("name", "expected a non-empty name");
  if (s.modules.empty()) Invalid("modules", "expected at least one module");
  std::set<std::string> seen;
  for (const auto& m : s.modules) {
    if (std::find_if(std::begin(kKnownModules), std::end(kKnownModules),
                     [&](const char* k) { return m == k; }) == std::end(kKnownModules)) {
      Invalid("modules", "unknown module '" + m +
                             "' (known: needle, tremor, thread, tissue, grasp, loop, knots, "
                             "placement)");
    }
    if (!seen.insert(m).second) Invalid("modules", "module '" + m + "' named twice");
  }
  const geometry::TorusSegmentDef& v = s.vessel;
  if (!(v.core_radius_m > 0)) Invalid("vessel.core_radius_m", "expected > 0");
  if (!(v.tube_radius_m > 0 && v.tube_radius_m < v.core_radius_m)) {
    Invalid("vessel.tube_radius_m", "expected 0 < tube radius < core radius");
  }
  if (!(v.segment_angle_rad > 0 && v.segment_angle_rad <= kTwoPi)) {
    Invalid("vessel.segment_angle_rad", "expected in (0, 2π]");
  }
  const geometry::ArcDef& n = s.needle;
  if (!(n.radius_m > 0)) Invalid("needle.radius_m", "expected > 0");
  if (s.HasModule("needle") && !(std::abs(n.radius_m - v.core_radius_m) < v.tube_radius_m)) {
    Invalid("needle.radius_m",
            "expected within the tube: |needle radius − core radius| < tube radius");
  }
  if (!(n.sweep_rad > 0 && n.sweep_rad <= kTwoPi))
    Invalid("needle.sweep_rad", "expected in (0, 2π]");
  const TaskDef& t = s.task;
  if (!(t.pass_duration_s > 0.1)) Invalid("task.pass_duration_s", "expected > 0.1 s");
  if (t.path == PathKind::kArc) {
    if (!(t.start_azimuth_rad >= 0 && t.start_azimuth_rad < t.end_azimuth_rad)) {
      Invalid("task.start_azimuth_rad", "expected 0 <= start < end");
    }
    if (s.HasModule("needle") && !(t.end_azimuth_rad + n.sweep_rad <= v.segment_angle_rad)) {
      Invalid("task.end_azimuth_rad", "expected end + needle sweep <= vessel segment angle");
    }
  }
  if (t.path == PathKind::kLine) {
    if (!((t.line_end_m - t.line_start_m).norm() > 0)) {
      Invalid("task.line_end_m", "expected a point other than task.line_start_m");
    }
    if (s.HasModule("needle")) Invalid("task.path", "the needle module needs path: arc");
  }
  if (s.HasModule("thread") != s.thread.has_value()) {
    Invalid("thread", s.thread ? "section given but 'thread' is not in modules"
                               : "section required by the 'thread' module");
  }
  if (s.HasModule("tissue") != s.tissue.has_value()) {
    Invalid("tissue", s.tissue ? "section given but 'tissue' is not in modules"
                               : "section required by the 'tissue' module");
  }
  if (s.thread) {
    const ThreadSceneDef& th = *s.thread;
    try {
      th.def.Validate();
    } catch (const std::invalid_argument& e) {
      Invalid("thread.params",
              std::string(e.what()) + " (" + th.params_path + " with the scene's time step)");
    }
    if (!(std::abs(th.def.time_step_s * s.haptic.rate_hz - 1.0) < 1e-9)) {
      Invalid("thread.params", "time_step_s: expected the haptic period 1 / haptic.rate_hz");
    }
    if (th.def.max_grasps < 2) Invalid("thread.params", "max_grasps: expected >= 2");
    if (!(std::abs(th.slack_side_W.norm() - 1.0) < 1e-9)) {
      Invalid("thread.slack_side", "expected a non-zero vector");
    }
    const double reach_m = (s.CalcIdealToolPose(0).translation() - th.p_W_anchor).norm();
    if (!(reach_m <= th.def.length_m * (1 + 1e-9))) {
      Invalid("thread.anchor_m",
              "expected within the thread's length of the tool's start point (the thread would "
              "start stretched)");
    }
    if (!(reach_m > 0.2 * th.def.length_m)) {
      Invalid("thread.anchor_m",
              "expected farther than a fifth of the thread's length from the "
              "tool's start point");
    }
    if (!(th.max_strain > 0 && th.max_strain <= 1)) Invalid("thread.max_strain", "expected (0, 1]");
    if (s.second_hand &&
        !((s.second_hand->X_WT_start.translation() - th.p_W_anchor).norm() <= 1e-12)) {
      Invalid("second_hand.position_m",
              "expected thread.anchor_m: the second tool holds the thread's node 0 there");
    }
  }
  if (s.HasModule("grasp") != s.grasp.has_value()) {
    Invalid("grasp", s.grasp ? "section given but 'grasp' is not in modules"
                             : "section required by the 'grasp' module");
  }
  if (s.grasp) {
    try {
      s.grasp->def.Validate();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("grasp." + std::string(e.what()));
    }
    if (!(s.grasp->p_W_object.z() > 0))
      Invalid("grasp.position_m", "expected above the table (z > 0)");
    if (!(s.grasp->lift_height_m > s.grasp->p_W_object.z())) {
      Invalid("grasp.lift_height_m", "expected above the object's resting height");
    }
  }
  if (s.HasModule("loop") != s.loop.has_value()) {
    Invalid("loop", s.loop ? "section given but 'loop' is not in modules"
                           : "section required by the 'loop' module");
  }
  if (s.loop) {
    try {
      s.loop->loop.Validate();
    } catch (const std::invalid_argument& e) {
      Invalid("loop.radius_m", e.what());
    }
    try {
      s.loop->wire.Validate();
    } catch (const std::invalid_argument& e) {
      Invalid("loop.course", e.what());
    }
    if (!(s.loop->wall_stiffness_N_per_m >= 0 && s.loop->wall_stiffness_N_per_m <= 1e5)) {
      Invalid("loop.wall_stiffness_N_per_m", "expected 0..1e5 N/m");
    }
  }
  if (s.HasModule("knots") != s.knots.has_value()) {
    Invalid("knots", s.knots ? "section given but 'knots' is not in modules"
                             : "section required by the 'knots' module");
  }
  if (s.knots) {
    if (s.knots->items.empty() || s.knots->items.size() > 32) {
      Invalid("knots.items", "expected 1..32 knots");
    }
    if (!(s.knots->thread_diameter_m > 0 && s.knots->thread_diameter_m <= 1e-3)) {
      Invalid("knots.thread_diameter_m", "expected (0, 1e-3] m");
    }
  }
  if (s.HasModule("placement") != s.placement.has_value()) {
    Invalid("placement", s.placement ? "section given but 'placement' is not in modules"
                                     : "section required by the 'placement' module");
  }
  if (s.placement) {
    const PlacementSceneDef& p = *s.placement;
    if (!(p.vessel_radius_m > 0)) Invalid("placement.vessel_radius_m", "expected > 0 m");
    if (!(p.stitches >= 2 && p.stitches <= 16)) Invalid("placement.stitches", "expected 2..16");
    if (!(p.bite_m > 0 && p.bite_m < p.end_height_m)) {
      Invalid("placement.bite_m", "expected 0 < bite < end_height_m");
    }
    if (!(p.move_s > 0.1 && p.move_s <= 30)) Invalid("placement.move_s", "expected (0.1, 30] s");
  }
  if (t.path == PathKind::kCircle) {
    if (!(t.circle_radius_m > 0)) Invalid("task.circle_radius_m", "expected > 0 m");
    if (!(t.start_azimuth_rad < t.end_azimuth_rad)) {
      Invalid("task.end_azimuth_rad", "expected start < end");
    }
    if (s.HasModule("needle")) Invalid("task.path", "the needle module needs path: arc");
  }
  if (t.kind == TaskKind::kNylonLoop && !(s.HasModule("thread") && t.path == PathKind::kCircle)) {
    Invalid("task.kind", "nylon_loop needs the thread module and path: circle");
  }
  if ((t.kind == TaskKind::kKnotTying) != s.knot_tying.has_value()) {
    Invalid(s.knot_tying ? "knot_tying" : "task.kind",
            s.knot_tying ? "section given but task.kind is not knot_tying"
                         : "knot_tying needs the knot_tying section");
  }
  if (s.knot_tying) {
    const KnotTyingSceneDef& k = *s.knot_tying;
    if (!s.HasModule("thread") || !s.second_hand) {
      Invalid("task.kind", "knot_tying needs the thread module and a second_hand");
    }
    if (!(k.throws >= 1 && k.throws <= 3)) Invalid("knot_tying.throws", "expected 1..3");
    if (!(k.speed_m_per_s > 0 && k.speed_m_per_s <= 0.02)) {
      Invalid("knot_tying.speed_m_per_s", "expected (0, 0.02] m/s");
    }
    for (const auto& [tension, field] :
         {std::pair{k.pull_tension_N, "knot_tying.pull_tension_N"},
          std::pair{k.throw_tension_N, "knot_tying.throw_tension_N"},
          std::pair{k.hold_tension_N, "knot_tying.hold_tension_N"}}) {
      if (!(tension > 0 && tension < 1)) Invalid(field, "expected a tension in (0, 1) N");
    }
    if (!(k.hold_s >= 0 && k.hold_s < t.time_limit_s)) {
      Invalid("knot_tying.hold_s", "expected 0 <= hold_s < task.time_limit_s");
    }
    if (!(k.stitch_relax_s >= 0 && k.stitch_relax_s <= 10)) {
      Invalid("knot_tying.stitch_relax_s", "expected a time in [0, 10] s (0: a rigid stitch)");
    }
    if (!(k.hold_pull_N_per_m >= 0 && k.hold_pull_N_per_m < 1e4)) {
      Invalid("knot_tying.hold_pull_N_per_m", "expected a gain in [0, 10000) N/m");
    }
    if (!(k.bite_tear_N >= 0 && k.bite_tear_N < 1)) {
      Invalid("knot_tying.bite_tear_N", "expected a load in [0, 1) N (0: the bite never tears)");
    }
    if (k.stitch_in_plane && !(k.stitch_relax_s > 0 && s.HasModule("tissue"))) {
      Invalid("knot_tying.stitch_in_plane",
              "the stitch moves in the tissue patch's plane: needs the tissue module and "
              "stitch_relax_s > 0");
    }
    if (k.bite_tear_N > 0 && !(k.stitch_relax_s > 0 && s.HasModule("tissue"))) {
      Invalid("knot_tying.bite_tear_N",
              "the bite tears the tissue patch: needs the tissue module and stitch_relax_s > 0");
    }
  }
  if (t.kind == TaskKind::kKnotPlacement && !s.HasModule("placement")) {
    Invalid("task.kind", "knot_placement needs the placement module");
  }
  if (t.kind == TaskKind::kKnotTopology && !s.HasModule("knots")) {
    Invalid("task.kind", "knot_topology needs the knots module");
  }
  if (t.kind == TaskKind::kLoopAlongWire && !s.HasModule("loop")) {
    Invalid("task.kind", "loop_along_wire needs the loop module");
  }
  if (t.kind == TaskKind::kGrasp && !s.HasModule("grasp")) {
    Invalid("task.kind", "grasp needs the grasp module");
  }
  if (t.kind == TaskKind::kGrasp && t.path != PathKind::kLine) {
    Invalid("task.path", "grasp needs path: line (from above the object down to it)");
  }
  if (s.tissue) {
    const TissueSceneDef& ti = *s.tissue;
    try {
      ti.def.Validate();
    } catch (const std::invalid_argument& e) {
      // "FIELD: reason": the scene's override of FIELD (or the tissue section when FIELD is not
      // overridden) with the parameter file's other values.
      throw std::invalid_argument("tissue." + std::string(e.what()) + " (" + ti.params_path +
                                  " with the scene's overrides)");
    }
    if (!(ti.display_level >= 1 && ti.display_level <= 6)) {
      Invalid("tissue.display_level", "expected 1..6 ((2^l + 1)^2 <= 16384 values)");
    }
    if (ti.display_level > ti.def.max_level) {
      Invalid("tissue.display_level", "expected <= the tissue's max_level");
    }
    if (!(ti.contact_radius_m >= 0 &&
          ti.contact_radius_m < 0.25 * std::min(ti.def.length_x_m, ti.def.length_y_m))) {
      Invalid("tissue.contact_radius_m", "expected 0 <= radius < a quarter of the patch");
    }
    if (!(ti.bar_length_m > 0 &&
          ti.bar_length_m < std::min(ti.def.length_x_m, ti.def.length_y_m))) {
      Invalid("tissue.bar_length_m", "expected 0 < length < the patch side");
    }
    if (!(ti.max_force_N > 0)) Invalid("tissue.max_force_N", "expected > 0 N");
  }
  if (!(t.passes >= 1 && t.passes <= 100)) Invalid("task.passes", "expected 1..100");
  if (!(t.time_limit_s > 0 && t.time_limit_s <= 3600)) {
    Invalid("task.time_limit_s", "expected (0, 3600] s");
  }
  if (!(t.tolerance_m > 0)) Invalid("task.tolerance_m", "expected > 0 m");
  if (t.kind == TaskKind::kTremorHold && !(t.hold_s > 0 && t.hold_s <= t.time_limit_s)) {
    Invalid("task.hold_s", "expected 0 < hold_s <= time_limit_s");
  }
  if (t.kind == TaskKind::kNeedleAlongTube && !s.HasModule("needle")) {
    Invalid("task.kind", "needle_along_tube needs the needle module");
  }
  const bool needle_tool = s.tissue && s.tissue->tool == TissueToolKind::kNeedle;
  if (needle_tool != s.puncture.has_value()) {
    Invalid("puncture", s.puncture ? "section given but tissue.tool is not needle"
                                   : "section required by tissue.tool: needle");
  }
  if (s.puncture) {
    try {
      s.puncture->def.Validate();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("puncture." + std::string(e.what()));
    }
  }
  if (t.kind == TaskKind::kNeedleThroughTissue && !(needle_tool && t.path == PathKind::kArc)) {
    Invalid("task.kind", "needle_through_tissue needs tissue.tool: needle and path: arc");
  }
  if (t.kind == TaskKind::kNeedleAlongTube && t.path != PathKind::kArc) {
    Invalid("task.path", "needle_along_tube needs path: arc");
  }
  if (t.kind != TaskKind::kFollowPath && s.scoring.empty()) {
    Invalid("scoring", std::string("required by task kind ") + TaskKindName(t.kind));
  }
  double weights = 0;
  for (const ScoreTermDef& term : s.scoring) {
    if (!(term.weight >= 0)) Invalid("scoring." + term.metric + ".weight", "expected >= 0");
    if (!(term.limit > 0)) Invalid("scoring." + term.metric + ".limit", "expected > 0");
    weights += term.weight;
  }
  if (!s.scoring.empty() && !(weights > 0)) Invalid("scoring", "expected a positive weight");
  if (!(s.microscope.magnification >= 1 && s.microscope.magnification <= 50)) {
    Invalid("microscope.magnification", "expected 1..50 (a surgical microscope: 10–20)");
  }
  for (const auto& [kind, param] : s.cues.on) {
    if (!s.cues.available.empty() && std::find(s.cues.available.begin(), s.cues.available.end(),
                                               kind) == s.cues.available.end()) {
      Invalid(std::string("cues.on.") + cues::CueKindName(kind), "not in cues.available");
    }
    if (const std::string why = cues::CheckCue(kind, param); !why.empty()) {
      Invalid(std::string("cues.on.") + cues::CueKindName(kind), why);
    }
  }
  const HapticDef& h = s.haptic;
  if (!(h.rate_hz >= 100 && h.rate_hz <= 10000)) Invalid("haptic.rate_hz", "expected 100..10000");
  if (!(h.max_force_N > 0 && h.max_force_N <= 20))
    Invalid("haptic.max_force_N", "expected (0, 20] N");
  if (!(h.max_torque_Nm > 0 && h.max_torque_Nm <= 1))
    Invalid("haptic.max_torque_Nm", "expected (0, 1] N m");
  if (!(h.wall_stiffness_N_per_m >= 0 && h.wall_stiffness_N_per_m <= 1e5)) {
    Invalid("haptic.wall_stiffness_N_per_m", "expected 0..1e5 N/m");
  }
}

SceneModel ParseScene(const std::string& yaml_text, const std::string& origin) {
  try {
    return ReadScene(YamlReader::FromText(yaml_text, origin));
  } catch (const InputError& e) {
    throw SceneError(e);
  }
}

SceneModel LoadScene(const std::string& path) {
  try {
    return ReadScene(YamlReader(path));
  } catch (const InputError& e) {
    throw SceneError(e);
  }
}

}  // namespace microdex::scene
