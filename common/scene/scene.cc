#include "common/scene/scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace microdex::scene {
namespace {

constexpr double kTwoPi = 6.283185307179586;

[[noreturn]] void Fail(const std::string& origin, const std::string& field,
                       const std::string& what) {
  throw SceneError(origin + ": " + field + ": " + what);
}

double ReadDouble(const YAML::Node& parent, const char* key, const std::string& prefix,
                  const std::string& origin, double fallback) {
  const YAML::Node n = parent[key];
  if (!n) return fallback;
  try {
    const double v = n.as<double>();
    if (!std::isfinite(v)) Fail(origin, prefix + key, "expected a finite number");
    return v;
  } catch (const YAML::Exception&) {
    Fail(origin, prefix + key,
         "expected a number (line " + std::to_string(n.Mark().line + 1) + ")");
  }
}

Eigen::Vector3d ReadVec3(const YAML::Node& parent, const char* key, const std::string& prefix,
                         const std::string& origin) {
  const YAML::Node n = parent[key];
  if (!n) return Eigen::Vector3d::Zero();
  if (!n.IsSequence() || n.size() != 3) Fail(origin, prefix + key, "expected [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    try {
      v[i] = n[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(origin, prefix + key, "expected three numbers");
    }
    if (!std::isfinite(v[i])) Fail(origin, prefix + key, "expected finite numbers");
  }
  return v;
}

Eigen::Matrix3d RotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

int ReadInt(const YAML::Node& parent, const char* key, const std::string& prefix,
            const std::string& origin, int fallback) {
  const YAML::Node n = parent[key];
  if (!n) return fallback;
  try {
    return n.as<int>();
  } catch (const YAML::Exception&) {
    Fail(origin, prefix + key,
         "expected an integer (line " + std::to_string(n.Mark().line + 1) + ")");
  }
}

std::string ReadString(const YAML::Node& parent, const char* key, const std::string& prefix,
                       const std::string& origin, const std::string& fallback) {
  const YAML::Node n = parent[key];
  if (!n) return fallback;
  if (!n.IsScalar()) Fail(origin, prefix + key, "expected a string");
  return n.as<std::string>();
}

// A parameter file named in the scene: relative names are taken from the scene's folder.
std::string ResolveBeside(const std::string& origin, const std::string& name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return name;
  const std::filesystem::path dir = std::filesystem::path(origin).parent_path();
  return (dir / p).lexically_normal().string();
}

void CheckKeys(const YAML::Node& map, const std::set<std::string>& allowed,
               const std::string& prefix, const std::string& origin) {
  for (const auto& kv : map) {
    const std::string k = kv.first.as<std::string>();
    if (!allowed.count(k)) Fail(origin, prefix + k, "unknown key");
  }
}

}  // namespace

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
  if (task.path == PathKind::kArc) return CalcIdealX_WT(CalcIdealAzimuth(t_s));
  const double u = CalcIdealPathFraction(t_s);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = task.R_WT_line;
  X.translation() = task.line_start_m + u * (task.line_end_m - task.line_start_m);
  return X;
}

Eigen::Isometry3d SceneModel::X_TN() const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translate(Eigen::Vector3d(-needle.radius_m, 0, 0));
  return X;
}

void ValidateScene(const SceneModel& s) {
  const std::string& o = s.path.empty() ? std::string("scene") : s.path;
  if (s.name.empty()) Fail(o, "name", "expected a non-empty name");
  if (s.modules.empty()) Fail(o, "modules", "expected at least one module");
  std::set<std::string> seen;
  for (const auto& m : s.modules) {
    if (std::find_if(std::begin(kKnownModules), std::end(kKnownModules),
                     [&](const char* k) { return m == k; }) == std::end(kKnownModules)) {
      Fail(o, "modules", "unknown module '" + m + "' (known: needle, tremor, thread, tissue)");
    }
    if (!seen.insert(m).second) Fail(o, "modules", "module '" + m + "' named twice");
  }
  const geometry::TorusSegmentDef& v = s.vessel;
  if (!(v.core_radius_m > 0)) Fail(o, "vessel.core_radius_m", "expected > 0");
  if (!(v.tube_radius_m > 0 && v.tube_radius_m < v.core_radius_m)) {
    Fail(o, "vessel.tube_radius_m", "expected 0 < tube radius < core radius");
  }
  if (!(v.segment_angle_rad > 0 && v.segment_angle_rad <= kTwoPi)) {
    Fail(o, "vessel.segment_angle_rad", "expected in (0, 2π]");
  }
  const geometry::ArcDef& n = s.needle;
  if (!(n.radius_m > 0)) Fail(o, "needle.radius_m", "expected > 0");
  if (!(std::abs(n.radius_m - v.core_radius_m) < v.tube_radius_m)) {
    Fail(o, "needle.radius_m",
         "expected within the tube: |needle radius − core radius| < tube radius");
  }
  if (!(n.sweep_rad > 0 && n.sweep_rad <= kTwoPi))
    Fail(o, "needle.sweep_rad", "expected in (0, 2π]");
  const TaskDef& t = s.task;
  if (!(t.pass_duration_s > 0.1)) Fail(o, "task.pass_duration_s", "expected > 0.1 s");
  if (t.path == PathKind::kArc) {
    if (!(t.start_azimuth_rad >= 0 && t.start_azimuth_rad < t.end_azimuth_rad)) {
      Fail(o, "task.start_azimuth_rad", "expected 0 <= start < end");
    }
    if (!(t.end_azimuth_rad + n.sweep_rad <= v.segment_angle_rad)) {
      Fail(o, "task.end_azimuth_rad", "expected end + needle sweep <= vessel segment angle");
    }
  }
  if (t.path == PathKind::kLine) {
    if (!((t.line_end_m - t.line_start_m).norm() > 0)) {
      Fail(o, "task.line_end_m", "expected a point other than task.line_start_m");
    }
    if (s.HasModule("needle")) Fail(o, "task.path", "the needle module needs path: arc");
  }
  if (s.HasModule("thread") != s.thread.has_value()) {
    Fail(o, "thread",
         s.thread ? "section given but 'thread' is not in modules"
                  : "section required by the 'thread' module");
  }
  if (s.HasModule("tissue") != s.tissue.has_value()) {
    Fail(o, "tissue",
         s.tissue ? "section given but 'tissue' is not in modules"
                  : "section required by the 'tissue' module");
  }
  if (s.thread) {
    const ThreadSceneDef& th = *s.thread;
    try {
      th.def.Validate();
    } catch (const std::invalid_argument& e) {
      Fail(o, "thread.params", th.params_path + ": " + e.what());
    }
    if (!(std::abs(th.def.time_step_s * s.haptic.rate_hz - 1.0) < 1e-9)) {
      Fail(o, "thread.params", "time_step_s: expected the haptic period 1 / haptic.rate_hz");
    }
    if (th.def.max_grasps < 2) Fail(o, "thread.params", "max_grasps: expected >= 2");
    if (!(std::abs(th.slack_side_W.norm() - 1.0) < 1e-9)) {
      Fail(o, "thread.slack_side", "expected a non-zero vector");
    }
    const double reach_m = (s.CalcIdealToolPose(0).translation() - th.p_W_anchor).norm();
    if (!(reach_m <= th.def.length_m * (1 + 1e-9))) {
      Fail(o, "thread.anchor_m",
           "expected within the thread's length of the tool's start point (the thread would "
           "start stretched)");
    }
    if (!(reach_m > 0.2 * th.def.length_m)) {
      Fail(o, "thread.anchor_m",
           "expected farther than a fifth of the thread's length from the "
           "tool's start point");
    }
    if (!(th.max_strain > 0 && th.max_strain <= 1)) Fail(o, "thread.max_strain", "expected (0, 1]");
  }
  if (s.tissue) {
    const TissueSceneDef& ti = *s.tissue;
    try {
      ti.def.Validate();
    } catch (const std::invalid_argument& e) {
      Fail(o, "tissue", ti.params_path + " with the scene's overrides: " + e.what());
    }
    if (!(ti.display_level >= 1 && ti.display_level <= 6)) {
      Fail(o, "tissue.display_level", "expected 1..6 ((2^l + 1)^2 <= 16384 values)");
    }
    if (ti.display_level > ti.def.max_level) {
      Fail(o, "tissue.display_level", "expected <= the tissue's max_level");
    }
    if (!(ti.contact_radius_m >= 0 &&
          ti.contact_radius_m < 0.25 * std::min(ti.def.length_x_m, ti.def.length_y_m))) {
      Fail(o, "tissue.contact_radius_m", "expected 0 <= radius < a quarter of the patch");
    }
    if (!(ti.bar_length_m > 0 &&
          ti.bar_length_m < std::min(ti.def.length_x_m, ti.def.length_y_m))) {
      Fail(o, "tissue.bar_length_m", "expected 0 < length < the patch side");
    }
    if (!(ti.max_force_N > 0)) Fail(o, "tissue.max_force_N", "expected > 0 N");
  }
  const HapticDef& h = s.haptic;
  if (!(h.rate_hz >= 100 && h.rate_hz <= 10000)) Fail(o, "haptic.rate_hz", "expected 100..10000");
  if (!(h.max_force_N > 0 && h.max_force_N <= 20))
    Fail(o, "haptic.max_force_N", "expected (0, 20] N");
  if (!(h.wall_stiffness_N_per_m >= 0 && h.wall_stiffness_N_per_m <= 1e5)) {
    Fail(o, "haptic.wall_stiffness_N_per_m", "expected 0..1e5 N/m");
  }
}

SceneModel ParseScene(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw SceneError(origin + ": not YAML: " + e.what());
  }
  if (!root.IsMap()) throw SceneError(origin + ": expected a YAML mapping at the top");
  CheckKeys(root, {"name", "modules", "vessel", "needle", "task", "haptic", "thread", "tissue"}, "",
            origin);
  SceneModel s;
  s.path = origin;
  try {
    if (root["name"]) s.name = root["name"].as<std::string>();
    if (!root["modules"] || !root["modules"].IsSequence()) {
      Fail(origin, "modules", "expected a list of module names");
    }
    for (const auto& m : root["modules"]) s.modules.push_back(m.as<std::string>());
  } catch (const YAML::Exception&) {
    Fail(origin, "name/modules", "expected strings");
  }
  if (const YAML::Node v = root["vessel"]) {
    CheckKeys(v, {"core_radius_m", "tube_radius_m", "segment_angle_rad", "position_m", "rpy_rad"},
              "vessel.", origin);
    s.vessel.core_radius_m =
        ReadDouble(v, "core_radius_m", "vessel.", origin, s.vessel.core_radius_m);
    s.vessel.tube_radius_m =
        ReadDouble(v, "tube_radius_m", "vessel.", origin, s.vessel.tube_radius_m);
    s.vessel.segment_angle_rad =
        ReadDouble(v, "segment_angle_rad", "vessel.", origin, s.vessel.segment_angle_rad);
    const Eigen::Vector3d p = ReadVec3(v, "position_m", "vessel.", origin);
    const Eigen::Vector3d rpy = ReadVec3(v, "rpy_rad", "vessel.", origin);
    s.vessel.X_WV = Eigen::Isometry3d::Identity();
    s.vessel.X_WV.translate(p);
    s.vessel.X_WV.rotate(RotationFromRpy(rpy));
  }
  if (const YAML::Node n = root["needle"]) {
    CheckKeys(n, {"radius_m", "sweep_rad"}, "needle.", origin);
    s.needle.radius_m = ReadDouble(n, "radius_m", "needle.", origin, s.needle.radius_m);
    s.needle.sweep_rad = ReadDouble(n, "sweep_rad", "needle.", origin, s.needle.sweep_rad);
  }
  if (const YAML::Node t = root["task"]) {
    CheckKeys(t,
              {"pass_duration_s", "start_azimuth_rad", "end_azimuth_rad", "path", "line_start_m",
               "line_end_m", "tool_rpy_rad"},
              "task.", origin);
    const std::string path = ReadString(t, "path", "task.", origin, "arc");
    if (path == "arc") {
      s.task.path = PathKind::kArc;
    } else if (path == "line") {
      s.task.path = PathKind::kLine;
    } else {
      Fail(origin, "task.path", "expected arc|line");
    }
    if (t["line_start_m"]) s.task.line_start_m = ReadVec3(t, "line_start_m", "task.", origin);
    if (t["line_end_m"]) s.task.line_end_m = ReadVec3(t, "line_end_m", "task.", origin);
    s.task.R_WT_line = RotationFromRpy(ReadVec3(t, "tool_rpy_rad", "task.", origin));
    s.task.pass_duration_s =
        ReadDouble(t, "pass_duration_s", "task.", origin, s.task.pass_duration_s);
    s.task.start_azimuth_rad =
        ReadDouble(t, "start_azimuth_rad", "task.", origin, s.task.start_azimuth_rad);
    s.task.end_azimuth_rad =
        ReadDouble(t, "end_azimuth_rad", "task.", origin, s.task.end_azimuth_rad);
  }
  if (const YAML::Node h = root["haptic"]) {
    CheckKeys(h, {"rate_hz", "max_force_N", "wall_stiffness_N_per_m"}, "haptic.", origin);
    s.haptic.rate_hz = ReadDouble(h, "rate_hz", "haptic.", origin, s.haptic.rate_hz);
    s.haptic.max_force_N = ReadDouble(h, "max_force_N", "haptic.", origin, s.haptic.max_force_N);
    s.haptic.wall_stiffness_N_per_m =
        ReadDouble(h, "wall_stiffness_N_per_m", "haptic.", origin, s.haptic.wall_stiffness_N_per_m);
  }
  if (const YAML::Node th = root["thread"]) {
    if (!th.IsMap()) Fail(origin, "thread", "expected a map");
    CheckKeys(th, {"params", "anchor_m", "slack_side", "floor_height_m", "max_strain"}, "thread.",
              origin);
    ThreadSceneDef d;
    const std::string params = ReadString(th, "params", "thread.", origin, "");
    if (params.empty()) Fail(origin, "thread.params", "expected a thread parameter file");
    d.params_path = ResolveBeside(origin, params);
    try {
      d.def = thread::LoadThreadDef(d.params_path);
    } catch (const std::exception& e) {
      Fail(origin, "thread.params", e.what());
    }
    // The thread steps once per haptic tick.
    d.def.time_step_s = 1.0 / s.haptic.rate_hz;
    d.p_W_anchor = ReadVec3(th, "anchor_m", "thread.", origin);
    if (th["slack_side"]) {
      const Eigen::Vector3d side = ReadVec3(th, "slack_side", "thread.", origin);
      d.slack_side_W = side.norm() > 0 ? Eigen::Vector3d(side.normalized()) : side;
    }
    d.floor_height_m = ReadDouble(th, "floor_height_m", "thread.", origin, d.floor_height_m);
    d.max_strain = ReadDouble(th, "max_strain", "thread.", origin, d.max_strain);
    s.thread = d;
  }
  if (const YAML::Node ti = root["tissue"]) {
    if (!ti.IsMap()) Fail(origin, "tissue", "expected a map");
    CheckKeys(ti,
              {"params", "position_m", "rpy_rad", "tool", "contact_radius_m", "bar_length_m",
               "display_level", "max_force_N", "level", "max_level", "solver", "grading",
               "cg_relative_tolerance", "cg_max_iterations"},
              "tissue.", origin);
    TissueSceneDef d;
    const std::string params = ReadString(ti, "params", "tissue.", origin, "");
    if (params.empty()) Fail(origin, "tissue.params", "expected a tissue parameter file");
    d.params_path = ResolveBeside(origin, params);
    try {
      d.def = fem::LoadTissueDef(d.params_path);
    } catch (const std::exception& e) {
      Fail(origin, "tissue.params", e.what());
    }
    // The scene's overrides of the parameter file (a station picks the level and solver that
    // fit its haptic period).
    d.def.level = ReadInt(ti, "level", "tissue.", origin, d.def.level);
    d.def.max_level = ReadInt(ti, "max_level", "tissue.", origin, d.def.max_level);
    d.def.grading = ReadDouble(ti, "grading", "tissue.", origin, d.def.grading);
    d.def.cg_relative_tolerance =
        ReadDouble(ti, "cg_relative_tolerance", "tissue.", origin, d.def.cg_relative_tolerance);
    d.def.cg_max_iterations =
        ReadInt(ti, "cg_max_iterations", "tissue.", origin, d.def.cg_max_iterations);
    if (ti["solver"]) {
      try {
        d.def.solver = fem::ParseSolverKind(ReadString(ti, "solver", "tissue.", origin, ""));
      } catch (const std::invalid_argument&) {
        Fail(origin, "tissue.solver", "expected cg|pcg_jacobi|pcg_ic|cholmod");
      }
    }
    const Eigen::Vector3d p = ReadVec3(ti, "position_m", "tissue.", origin);
    d.X_WS = Eigen::Isometry3d::Identity();
    d.X_WS.translate(p);
    d.X_WS.rotate(RotationFromRpy(ReadVec3(ti, "rpy_rad", "tissue.", origin)));
    const std::string tool = ReadString(ti, "tool", "tissue.", origin, "point");
    if (tool == "point") {
      d.tool = TissueToolKind::kPoint;
    } else if (tool == "bar") {
      d.tool = TissueToolKind::kBar;
    } else {
      Fail(origin, "tissue.tool", "expected point|bar");
    }
    d.contact_radius_m = ReadDouble(ti, "contact_radius_m", "tissue.", origin, d.contact_radius_m);
    d.bar_length_m = ReadDouble(ti, "bar_length_m", "tissue.", origin, d.bar_length_m);
    d.display_level = ReadInt(ti, "display_level", "tissue.", origin, d.display_level);
    d.max_force_N = ReadDouble(ti, "max_force_N", "tissue.", origin, d.max_force_N);
    s.tissue = d;
  }
  ValidateScene(s);
  s.needle.X_WN = s.CalcIdealX_WT(s.task.start_azimuth_rad) * s.X_TN();
  return s;
}

SceneModel LoadScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseScene(ss.str(), path);
}

}  // namespace microdex::scene
