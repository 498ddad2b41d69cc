#include "common/scene/scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
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
  const VesselDef& v = s.vessel;
  if (!(v.core_radius_m > 0)) Fail(o, "vessel.core_radius_m", "expected > 0");
  if (!(v.tube_radius_m > 0 && v.tube_radius_m < v.core_radius_m)) {
    Fail(o, "vessel.tube_radius_m", "expected 0 < tube radius < core radius");
  }
  if (!(v.segment_angle_rad > 0 && v.segment_angle_rad <= kTwoPi)) {
    Fail(o, "vessel.segment_angle_rad", "expected in (0, 2π]");
  }
  const NeedleDef& n = s.needle;
  if (!(n.radius_m > 0)) Fail(o, "needle.radius_m", "expected > 0");
  if (!(std::abs(n.radius_m - v.core_radius_m) < v.tube_radius_m)) {
    Fail(o, "needle.radius_m",
         "expected within the tube: |needle radius − core radius| < tube radius");
  }
  if (!(n.sweep_rad > 0 && n.sweep_rad <= kTwoPi))
    Fail(o, "needle.sweep_rad", "expected in (0, 2π]");
  const TaskDef& t = s.task;
  if (!(t.pass_duration_s > 0.1)) Fail(o, "task.pass_duration_s", "expected > 0.1 s");
  if (!(t.start_azimuth_rad >= 0 && t.start_azimuth_rad < t.end_azimuth_rad)) {
    Fail(o, "task.start_azimuth_rad", "expected 0 <= start < end");
  }
  if (!(t.end_azimuth_rad + n.sweep_rad <= v.segment_angle_rad)) {
    Fail(o, "task.end_azimuth_rad", "expected end + needle sweep <= vessel segment angle");
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
  CheckKeys(root, {"name", "modules", "vessel", "needle", "task", "haptic"}, "", origin);
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
    s.vessel.X_WV.rotate(Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()));
  }
  if (const YAML::Node n = root["needle"]) {
    CheckKeys(n, {"radius_m", "sweep_rad"}, "needle.", origin);
    s.needle.radius_m = ReadDouble(n, "radius_m", "needle.", origin, s.needle.radius_m);
    s.needle.sweep_rad = ReadDouble(n, "sweep_rad", "needle.", origin, s.needle.sweep_rad);
  }
  if (const YAML::Node t = root["task"]) {
    CheckKeys(t, {"pass_duration_s", "start_azimuth_rad", "end_azimuth_rad"}, "task.", origin);
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
  ValidateScene(s);
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
