#pragma once
// A scene: the immutable description of one training task (DESIGN.md principle 1), loaded
// once from YAML and validated. It names the modules a station builds; a station builds only
// those and publishes only their topics.
//
// Minimal for now: the needle-in-tube primitive (thesis §2.2, Fig. 2.2c: "needle maneuvering
// along a curved tube"): a curved needle held at its tail must slide along a tube, the
// segment of a torus, without touching its wall.

#include <Eigen/Geometry>
#include <stdexcept>
#include <string>
#include <vector>

namespace microdex::scene {

// Bad scene file: the message names the file, the field and what was expected.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Modules a scene may name. "thread" and "tissue" are known names whose station modules are
// not built yet; a station refuses them clearly.
inline constexpr const char* kKnownModules[] = {"needle", "tremor", "thread", "tissue"};

// The tube: a torus segment (same conventions as geometry::TorusSegmentDef).
struct VesselDef {
  double core_radius_m = 5e-3;
  double tube_radius_m = 0.5e-3;
  double segment_angle_rad = 4.71238898038469;  // 270°
  Eigen::Isometry3d X_WV = Eigen::Isometry3d::Identity();
};

// The needle: an arc of radius radius_m and sweep sweep_rad, held at its s = 0 end.
struct NeedleDef {
  double radius_m = 5e-3;
  double sweep_rad = 1.0471975511965976;  // 60°
};

// The task: passes of the needle tail along its path circle, from start to end azimuth and
// back, each pass lasting pass_duration_s (minimum-jerk timing).
struct TaskDef {
  double pass_duration_s = 4.0;
  double start_azimuth_rad = 0.2;
  double end_azimuth_rad = 3.3;
};

// Haptic rendering limits.
struct HapticDef {
  double rate_hz = 1000;
  double max_force_N = 2.0;                // every force sent to a device is saturated here
  double wall_stiffness_N_per_m = 1000.0;  // penalty force of the tube wall on contact
};

struct SceneModel {
  std::string path;  // where it was loaded from ("" when parsed from text)
  std::string name;
  std::vector<std::string> modules;
  VesselDef vessel;
  NeedleDef needle;
  TaskDef task;
  HapticDef haptic;

  bool HasModule(const std::string& module) const;
  // The scripted ideal tool pose at azimuth theta: the needle tail on its path circle (radius
  // needle.radius_m about the vessel axis), the needle lying along the core circle.
  Eigen::Isometry3d CalcIdealX_WT(double theta_rad) const;
  // The scripted azimuth of the tool at time t: passes from start to end and back, each with
  // minimum-jerk timing θ = a + (b − a)(10τ³ − 15τ⁴ + 6τ⁵), τ the fraction of the pass.
  double CalcIdealAzimuth(double t_s) const;
  // The needle frame N from the tool frame T (the tail point, s = 0): X_WN = X_WT * X_TN.
  Eigen::Isometry3d X_TN() const;
};

// Throws SceneError naming the first bad field. Called by the loaders.
void ValidateScene(const SceneModel& scene);

// Loads and validates a scene file. Throws SceneError.
SceneModel LoadScene(const std::string& path);
// The same from YAML text; origin names it in error messages.
SceneModel ParseScene(const std::string& yaml_text, const std::string& origin);

}  // namespace microdex::scene
