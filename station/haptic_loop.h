#pragma once
// The haptic thread's work: one step reads the device, applies the cues that are due, steps
// the scene's modules, writes a finite saturated force, updates the score and pushes a
// snapshot into the ring. Run() paces the steps on absolute deadlines of an injected clock.
//
// Tick() and Run() never allocate, lock, log or block (beyond the clock's sleep): everything
// is sized in the constructor. A test runs them under an allocation counter.

#include <atomic>
#include <memory>
#include <vector>

#include "common/cues/path_force_field.h"
#include "common/cues/tremor_filter.h"
#include "common/scene/scene.h"
#include "station/device.h"
#include "station/module.h"
#include "station/rt/clock.h"
#include "station/rt/spsc_ring.h"
#include "station/snapshot.h"

namespace microdex::station {

// The handoffs of one station (station/rt/spsc_ring.h).
struct StationRings {
  explicit StationRings(std::size_t snapshot_capacity = 4096, std::size_t cue_capacity = 64)
      : snapshots(snapshot_capacity), cues(cue_capacity) {}
  rt::SpscRing<TickSnapshot> snapshots;  // producer: haptic thread; consumer: publisher thread
  rt::SpscRing<CueRequest> cues;         // producer: publisher thread; consumer: haptic thread
  LargeFrames frames;                    // producer: haptic thread; consumer: publisher thread
};

// Cue limits: a request outside them is rejected before it reaches the haptic thread.
inline constexpr double kMaxFieldStiffness_N_per_m = 2000;
inline constexpr double kMaxTremorGain = 20;
// Empty when the cue can be applied; otherwise why not.
const char* CheckCue(net::CueKind kind, double param);

class HapticLoop {
 public:
  static constexpr int kMaxPendingCues = 32;

  // frame_period_steps: the modules write their large frames (thread nodes, tissue field)
  // every that many steps (the mirror period), starting at step 0.
  HapticLoop(const scene::SceneModel& scene, Device& device,
             std::vector<std::unique_ptr<Module>> modules, StationRings& rings, rt::Clock& clock,
             int frame_period_steps = 16);

  // One step, started at tick_start_ns (monotonic) with the given period since the previous
  // start; stamp_ns is the CLOCK_REALTIME source stamp.
  void Tick(std::int64_t tick_start_ns, std::int64_t period_ns, std::int64_t stamp_ns,
            bool overrun);

  // Steps on absolute deadlines until `stop` or max_steps. A tick that starts more than one
  // period after its deadline counts as an overrun; after a stall of more than
  // kResyncPeriods periods the deadlines restart from now instead of catching up in a burst.
  void Run(const std::atomic<bool>& stop, std::uint64_t max_steps);
  static constexpr int kResyncPeriods = 10;

  std::uint64_t step() const { return step_; }
  std::uint64_t ring_dropped() const { return ring_dropped_.load(std::memory_order_relaxed); }
  std::uint64_t overruns() const { return overruns_; }
  const TickSnapshot& last_snapshot() const { return snap_; }
  double dt_s() const { return dt_s_; }
  // What module i's error estimate measures (a constant string; any thread may ask).
  const char* module_error_kind(std::size_t i) const { return modules_[i]->error_kind(); }
  // Module i, for tests and tools on the haptic thread's side (or after Run returned).
  const Module& module(std::size_t i) const { return *modules_[i]; }
  std::size_t module_count() const { return modules_.size(); }

 private:
  void TakeDueCues();
  void ApplyCue(const CueRequest& cue);
  void UpdateScore(const Eigen::Vector3d& p_device, TickSnapshot& s);

  const scene::SceneModel& scene_;
  Device& device_;
  std::vector<std::unique_ptr<Module>> modules_;
  StationRings& rings_;
  rt::Clock& clock_;
  double dt_s_;
  std::int64_t period_ns_;
  int frame_period_steps_;
  std::uint64_t step_ = 0;
  std::uint64_t overruns_ = 0;
  std::atomic<std::uint64_t> ring_dropped_{0};
  std::uint32_t force_warnings_ = 0;

  // Cues.
  CueRequest pending_[kMaxPendingCues];
  int pending_count_ = 0;
  double field_stiffness_N_per_m_ = 0;  // > 0 convergent, < 0 divergent, 0 none
  double tremor_gain_ = 1;
  cues::IdealPath path_;
  cues::TremorFilterModel tremor_filter_;
  cues::TremorFilterState tremor_state_;

  // Score and events. A fault episode (needle contact, overstretched thread, tissue pressed too
  // hard) ends after kContactReleaseSteps steps without fault, so tremor at the limit does not
  // count as hundreds of episodes.
  static constexpr int kContactReleaseSteps = 50;
  bool in_episode_ = false;
  int steps_free_ = 0;
  bool have_prev_ = false;
  Eigen::Vector3d p_device_prev_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_ideal_prev_ = Eigen::Vector3d::Zero();
  TickSnapshot snap_;
};

}  // namespace microdex::station
