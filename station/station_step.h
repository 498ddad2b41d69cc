#pragma once
// One step of a station's simulation: (simulation, input, state) → state.
//
// The Simulation is what does not change while the station runs — the scene, the scene's
// modules (their models and their caches), the guidance path and the tremor filter — built
// once from the scene. state::StationState is everything that does. StepStation is the one
// place where the device sample and the instructor's cues enter the simulation:
//
//   StepStation
//     TakeCues         queue the cue requests of this input; apply those due (state.cues)
//     CalcToolAfterCues  tremor band of the raw device motion, amplified tremor → tool pose
//     CalcCueForce     guidance / destabilising field on the tool; LimitCueForce: finite,
//                      saturated and rate-limited (state.cues.f_cue_W)
//     StepModules      each module of the scene, in the scene's order (module sections; the
//                      wall forces scaled by the wall cue)
//     LimitToolWrench  force and torque (the modules' ToolTorque, about the tool point):
//                      finite and saturated, always; ramped to zero at the limiter's rate
//                      during a device fault (state.tool; bimanual: state.second_tool too,
//                      from the modules' SecondToolForce)
//     UpdateScore      running totals and fault episodes (state.score)
//     UpdateTask       deviation from the path or target, passes, the task's outcome
//                      (state.score; both frozen once the task has ended)
//     UpdateCueSignals clearance, deviation, click, error, the end-point prediction and its
//                      warning: what the visual and audio cues show (state.cues)
//
// Given a scene, a seed and the input stream (device samples and cue requests), the states
// are bit-for-bit the same on the same build: tests/unit/station/station_step_test.cc.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "common/cues/end_point_predictor.h"
#include "common/cues/force_limits.h"
#include "common/cues/path_force_field.h"
#include "common/cues/tremor_filter.h"
#include "common/scene/scene.h"
#include "common/state/station_state.h"
#include "station/device.h"
#include "station/module.h"
#include "station/rt/clock.h"
#include "station/snapshot.h"

namespace microdex::station {

// What enters a step from outside: the device sample and the cue requests that arrived since
// the previous step (each applied at the first step >= its apply_at_step).
struct StationInput {
  DeviceSample device;
  std::span<const state::CueRequest> cues;
  // Bimanual scenes (scene.hands() == 2): the second device's sample; ignored otherwise.
  DeviceSample second;
};

class Simulation {
 public:
  // Builds the scene's modules (throws std::runtime_error naming a module this build lacks).
  explicit Simulation(const scene::SceneModel& scene);

  // The state at the task's start: every module's section, the generator seeded.
  state::StationState MakeInitialState(std::uint64_t seed) const;

  const scene::SceneModel& scene() const { return scene_; }
  // The task's ideal path (what the guidance fields and the visual cues use).
  const cues::IdealPath& path() const { return path_; }
  double dt_s() const { return dt_s_; }
  std::size_t module_count() const { return modules_.size(); }
  const Module& module(std::size_t i) const { return *modules_[i]; }
  Module& module(std::size_t i) { return *modules_[i]; }

  // When set, StepStation times each module's step with this clock (telemetry only).
  void set_step_clock(rt::Clock* clock) { step_clock_ = clock; }
  // Wall time of module i's last step (0 without a step clock).
  double last_step_time_s(std::size_t i) const { return step_time_s_[i]; }

 private:
  friend void StepStation(Simulation&, const StationInput&, state::StationState&);

  const scene::SceneModel& scene_;
  double dt_s_;
  std::vector<std::unique_ptr<Module>> modules_;
  cues::IdealPath path_;
  cues::TremorFilterModel tremor_filter_;
  cues::EndPointPredictorModel predictor_;
  rt::Clock* step_clock_ = nullptr;
  std::vector<double> step_time_s_;
};

// The device sample as a recording keeps it: the rotation rebuilt from its quaternion
// (w, x, y, z), which is returned. A replay that rebuilds the rotation from the recorded
// quaternion (DeviceSampleFromRecord) then steps bit for bit alike. Called on every sample
// before StepStation (HapticLoop::Tick, RunSceneWithTrainee).
Eigen::Quaterniond CanonicalizeDeviceSample(DeviceSample& d);
// The sample a recorded (p, q, gripper, buttons) stands for.
DeviceSample DeviceSampleFromRecord(const Eigen::Vector3d& p_WT, const Eigen::Quaterniond& q_WT,
                                    double gripper, std::uint32_t buttons);

// Advances the state by one step. Never allocates, locks, logs or throws.
void StepStation(Simulation& sim, const StationInput& in, state::StationState& state);

// The snapshot's share of the state after a step (everything but the tick's timing).
void ProjectSnapshot(const Simulation& sim, const state::StationState& state, TickSnapshot& out);

using cues::CheckCue;  // cue limits: common/cues/cue_kind.h

}  // namespace microdex::station
