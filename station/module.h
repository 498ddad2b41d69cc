#pragma once
// The station's physics module interface: init from the scene (constructor and InitState),
// step, telemetry, frame. A scene names its modules; MakeModules builds exactly those:
// needle–vessel, tremor, thread, tissue.
//
// A module object holds only what does not change while the station runs (its model, built
// from the scene) and caches derived from the state (its workspace: factorisations, BVHs,
// the adapted mesh). Everything that changes is its section of state::StationState, which
// Step reads and writes: a module stepped from a copied state continues exactly as the
// original (tests/unit/station/station_step_test.cc).

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "common/scene/scene.h"
#include "common/state/station_state.h"
#include "station/snapshot.h"

namespace microdex::station {

// What a module reads each step besides the state.
struct ToolInput {
  std::uint64_t step = 0;
  double dt_s = 1e-3;
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  // the tool after cues
  Eigen::Vector3d p_WT_device = Eigen::Vector3d::Zero();   // the raw device position
  // Bimanual scenes: the second tool (state.second_tool); null with one hand.
  const state::ToolState* second_tool = nullptr;
};

// A module's report after a step, read from the state.
struct ModuleStatus {
  // True while the trainee is at fault in this module's task (needle touching the wall,
  // thread overstretched, tissue pressed too hard); value says how much.
  bool fault = false;
  double fault_value = 0;
  // The latest error estimate (NaN when none) and the running count of numerical warnings.
  double error_estimate = std::numeric_limits<double>::quiet_NaN();
  std::uint32_t warnings = 0;
};

class Module {
 public:
  virtual ~Module() = default;
  virtual const char* name() const = 0;
  // What the error estimate measures (a constant string).
  virtual const char* error_kind() const { return "none"; }
  // Puts this module's section, at the task's start, into the state.
  virtual void InitState(state::StationState& state) const = 0;
  // Reads the tool and this module's section of the state, writes the section, adds the
  // module's force on the tool to f_T_W. Never allocates, locks, logs or throws; numerical
  // trouble is counted in the section's warnings.
  virtual void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) = 0;
  virtual ModuleStatus Status(const state::StationState& state) const = 0;
  // This module's torque on the (first) tool about the tool point (X_WT's origin), world, N m,
  // after its last Step, read from its section of the state: a force pushing off-centre (the
  // needle's wall contact at the needle point, a grasped object's contacts on the jaws).
  virtual Eigen::Vector3d ToolTorque(const state::StationState& /*state*/) const {
    return Eigen::Vector3d::Zero();
  }
  // Bimanual scenes: this module's force on the second tool after its last Step, read from
  // its section of the state (zero for a module the second tool does not touch).
  virtual Eigen::Vector3d SecondToolForce(const state::StationState& /*state*/) const {
    return Eigen::Vector3d::Zero();
  }
  // Every mirror period: fills and publishes its large frame (thread nodes, tissue field), if
  // it has one. Same rules as Step.
  virtual void WriteFrame(const state::StationState& /*state*/, std::uint64_t /*step*/,
                          std::int64_t /*stamp_ns*/, LargeFrames& /*frames*/) {}
};

// Builds the scene's modules in the scene's order. Throws std::runtime_error naming a module
// that this build cannot provide.
std::vector<std::unique_ptr<Module>> MakeModules(const scene::SceneModel& scene);

}  // namespace microdex::station
