#include "station/haptic_loop.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include "common/base/check.h"
#include "common/state/state_hash.h"

namespace microdex::station {

HapticLoop::HapticLoop(const scene::SceneModel& scene, Device& device, StationRings& rings,
                       rt::Clock& clock, const HapticLoopConfig& config, Device* second_device)
    : sim_(scene),
      device_(device),
      second_device_(second_device),
      rings_(rings),
      clock_(clock),
      config_(config),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / scene.haptic.rate_hz))),
      state_(sim_.MakeInitialState(config.seed)) {
  if ((second_device_ != nullptr) != (scene.hands() == 2)) {
    throw std::invalid_argument(scene.path + ": the scene's trainee holds " +
                                std::to_string(scene.hands()) + " tool(s); the station was given " +
                                (second_device_ != nullptr ? "2 devices" : "1 device"));
  }
  MICRODEX_CHECK(config_.frame_period_steps >= 1);
  MICRODEX_CHECK(config_.hash_period_steps >= 0);
  sim_.set_step_clock(&clock_);
}

void HapticLoop::Tick(std::int64_t tick_start_ns, std::int64_t period_ns, std::int64_t stamp_ns,
                      bool overrun) {
  const std::uint64_t step = state_.step;
  // Input: the device sample and the cue requests that arrived (no more than there is room
  // for; the rest stay in the ring for the next step).
  StationInput in;
  in.device = device_.Read(step);
  const Eigen::Quaterniond q_device = CanonicalizeDeviceSample(in.device);
  Eigen::Quaterniond q_second = Eigen::Quaterniond::Identity();
  if (second_device_ != nullptr) {
    in.second = second_device_->Read(step);
    q_second = CanonicalizeDeviceSample(in.second);
  }
  int n = 0;
  const int room = state::kMaxPendingCues - state_.cues.pending_count;
  while (n < room && rings_.cues.TryPop(arrived_[n])) ++n;
  in.cues = std::span<const state::CueRequest>(arrived_.data(), static_cast<std::size_t>(n));

  StepStation(sim_, in, state_);
  device_.WriteWrench(state_.tool.f_T_W, state_.tool.tau_T_W);
  if (second_device_ != nullptr) {
    second_device_->WriteWrench(state_.second_tool->f_T_W, state_.second_tool->tau_T_W);
  }

  if (step % static_cast<std::uint64_t>(config_.frame_period_steps) == 0) {
    for (std::size_t i = 0; i < sim_.module_count(); ++i) {
      sim_.module(i).WriteFrame(state_, step, stamp_ns, rings_.frames);
    }
  }
  TickSnapshot& s = snap_;
  ProjectSnapshot(sim_, state_, s);
  s.q_WT_device = {q_device.w(), q_device.x(), q_device.y(), q_device.z()};  // as stepped
  s.second.q_WT_device = {q_second.w(), q_second.x(), q_second.y(), q_second.z()};
  s.tick_start_ns = tick_start_ns;
  s.stamp_ns = stamp_ns;
  s.period_ns = period_ns;
  s.overrun = overrun ? 1 : 0;
  s.has_state_hash = config_.hash_period_steps > 0 &&
                     step % static_cast<std::uint64_t>(config_.hash_period_steps) == 0;
  // Every step (a few µs for the largest state): the recording checks each one.
  s.step_hash = state::CalcStateHash(state_);
  s.state_hash = s.has_state_hash ? s.step_hash : 0;
  while (!rings_.snapshots.TryPush(s)) {
    if (!config_.wait_for_ring) {
      ring_dropped_.fetch_add(1, std::memory_order_relaxed);
      break;
    }
    std::this_thread::yield();  // unpaced only: the publisher drains the ring
  }
}

void HapticLoop::Run(const std::atomic<bool>& stop, std::uint64_t max_steps) {
  std::int64_t deadline = clock_.NowNs();
  std::int64_t prev_start = -1;
  while (!stop.load(std::memory_order_relaxed) && state_.step < max_steps) {
    deadline += period_ns_;
    bool sample = false;
    if (device_.paces_loop()) {
      // An external driver's servo loop paces the ticks: a tick follows each of its samples
      // (not before half a period after the last tick), or comes half a period after its
      // deadline when none arrives, so that the loop keeps its period through a fault.
      clock_.SleepUntilNs(deadline - period_ns_ / 2);
      sample = device_.WaitForSample(deadline + period_ns_ / 2);
    } else {
      clock_.SleepUntilNs(deadline);
    }
    const std::int64_t start = clock_.NowNs();
    if (sample) deadline = start;  // in phase with the driver
    const std::int64_t late = start - deadline;
    const bool overrun = late > period_ns_;
    if (overrun) ++overruns_;
    Tick(start, prev_start < 0 ? period_ns_ : start - prev_start, clock_.RealtimeNs(), overrun);
    prev_start = start;
    if (late > kResyncPeriods * period_ns_) deadline = start;
    if (config_.stop_at_task_end && state_.score.outcome != 0) break;
  }
}

}  // namespace microdex::station
