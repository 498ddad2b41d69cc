#pragma once
// The haptic thread's work: one tick reads the device, takes the cue requests that arrived,
// runs one StepStation on the station's state, writes the force to the device, and pushes a
// snapshot (a projection of the state) into the ring; every frame period the modules' large
// frames, every hash period the state hash. Run() paces the ticks on absolute deadlines of an
// injected clock.
//
// The loop owns the station's one StationState; nothing else holds simulation state.
// Tick() and Run() never allocate, lock, log or block (beyond the clock's sleep): everything
// is sized in the constructor. A test runs them under an allocation counter.

#include <atomic>
#include <memory>

#include "common/scene/scene.h"
#include "common/state/station_state.h"
#include "station/device.h"
#include "station/rt/clock.h"
#include "station/rt/spsc_ring.h"
#include "station/snapshot.h"
#include "station/station_step.h"

namespace microdex::station {

// The handoffs of one station (station/rt/spsc_ring.h).
struct StationRings {
  explicit StationRings(std::size_t snapshot_capacity = 4096, std::size_t cue_capacity = 64)
      : snapshots(snapshot_capacity), cues(cue_capacity) {}
  rt::SpscRing<TickSnapshot> snapshots;  // producer: haptic thread; consumer: publisher thread
  rt::SpscRing<state::CueRequest> cues;  // producer: publisher thread; consumer: haptic thread
  LargeFrames frames;                    // producer: haptic thread; consumer: publisher thread
};

struct HapticLoopConfig {
  std::uint64_t seed = 1;
  // The modules write their large frames (thread nodes, tissue field) every that many steps
  // (the mirror period), starting at step 0.
  int frame_period_steps = 16;
  // The state hash is taken after every step whose index is a multiple of this (1000: once
  // a second at 1 kHz, the telemetry's hash); 0: never.
  int hash_period_steps = 1000;
  // Unpaced runs only (--unpaced, not real time): when the snapshot ring is full the haptic
  // thread yields until the publisher has drained it, so that no snapshot is lost and the final
  // score is the last step's. Paced runs drop and count (ring_dropped) instead of waiting.
  bool wait_for_ring = false;
  // Stop after the step at which the scene's task ends (completed or at its time limit): a
  // simulated trainee's run is over then. A trainee at a device goes on (the scores freeze).
  bool stop_at_task_end = true;
};

class HapticLoop {
 public:
  // A bimanual scene (scene.hands() == 2) takes the second tool's device as second_device
  // (throws std::invalid_argument when the number of devices does not match the scene's
  // hands). The first device paces the loop when it is the pacing kind; the second is read as
  // it is at each tick.
  HapticLoop(const scene::SceneModel& scene, Device& device, StationRings& rings, rt::Clock& clock,
             const HapticLoopConfig& config = {}, Device* second_device = nullptr);

  // One step, started at tick_start_ns (monotonic) with the given period since the previous
  // start; stamp_ns is the CLOCK_REALTIME source stamp.
  void Tick(std::int64_t tick_start_ns, std::int64_t period_ns, std::int64_t stamp_ns,
            bool overrun);

  // Steps on absolute deadlines until `stop` or max_steps. A tick that starts more than one
  // period after its deadline counts as an overrun; after a stall of more than
  // kResyncPeriods periods the deadlines restart from now instead of catching up in a burst.
  void Run(const std::atomic<bool>& stop, std::uint64_t max_steps);
  static constexpr int kResyncPeriods = 10;

  std::uint64_t step() const { return state_.step; }
  std::uint64_t ring_dropped() const { return ring_dropped_.load(std::memory_order_relaxed); }
  std::uint64_t overruns() const { return overruns_; }
  const TickSnapshot& last_snapshot() const { return snap_; }
  double dt_s() const { return sim_.dt_s(); }
  // The station's state and simulation, for tests and tools on the haptic thread's side (or
  // after Run returned).
  const state::StationState& state() const { return state_; }
  const Simulation& simulation() const { return sim_; }
  // What module i's error estimate measures (a constant string; any thread may ask).
  const char* module_error_kind(std::size_t i) const { return sim_.module(i).error_kind(); }
  std::size_t module_count() const { return sim_.module_count(); }

 private:
  Simulation sim_;
  Device& device_;
  Device* second_device_;
  StationRings& rings_;
  rt::Clock& clock_;
  HapticLoopConfig config_;
  std::int64_t period_ns_;
  state::StationState state_;
  std::uint64_t overruns_ = 0;
  std::atomic<std::uint64_t> ring_dropped_{0};
  std::array<state::CueRequest, state::kMaxPendingCues> arrived_{};
  TickSnapshot snap_;
};

}  // namespace microdex::station
