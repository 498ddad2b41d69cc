#pragma once
// The station's physics module interface (DESIGN.md principle 2): init from the scene
// (constructor/factory), step, telemetry (step time, error estimate), snapshot. A scene
// names its modules; MakeModules builds exactly those: needle–vessel, tremor, thread, tissue.

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "common/scene/scene.h"
#include "station/snapshot.h"

namespace microdex::station {

// What a module reads each step.
struct ToolInput {
  std::uint64_t step = 0;
  double dt_s = 1e-3;
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  // the tool after cues
  Eigen::Vector3d p_WT_device = Eigen::Vector3d::Zero();   // the raw device position
};

class Module {
 public:
  virtual ~Module() = default;
  virtual const char* name() const = 0;
  // Reads the tool, updates this module's state, adds its force on the tool to f_T_W.
  // Never allocates, locks, logs or throws; numerical trouble is counted in warnings().
  virtual void Step(const ToolInput& in, Eigen::Vector3d& f_T_W) = 0;
  // Copies its state into the snapshot section it owns.
  virtual void WriteSnapshot(TickSnapshot& snapshot) const = 0;
  // Every mirror period: fills and publishes its large frame (thread nodes, tissue field),
  // if it has one. Same rules as Step.
  virtual void WriteFrame(std::uint64_t /*step*/, std::int64_t /*stamp_ns*/,
                          LargeFrames& /*frames*/) {}
  // True while the trainee is at fault in this module's task (needle touching the wall,
  // thread overstretched, tissue pressed too hard); fault_value() says how much.
  virtual bool fault() const { return false; }
  virtual double fault_value() const { return 0; }
  // Telemetry: the latest error estimate (NaN when none) and what it measures.
  virtual double error_estimate() const { return std::numeric_limits<double>::quiet_NaN(); }
  virtual const char* error_kind() const { return "none"; }
  virtual std::uint32_t warnings() const { return 0; }
};

// Builds the scene's modules in the scene's order. Throws std::runtime_error naming a module
// that this build cannot provide.
std::vector<std::unique_ptr<Module>> MakeModules(const scene::SceneModel& scene);

}  // namespace microdex::station
