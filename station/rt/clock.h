#pragma once
// The haptic loop's time source, injected so tests run the loop without wall-clock time
// (time is a dependency like any other). MonotonicClock is the real one: absolute deadlines on
// CLOCK_MONOTONIC with clock_nanosleep(TIMER_ABSTIME), source stamps from CLOCK_REALTIME. Neither
// allocates.
//
// A MonotonicClock with a spin tail sleeps until `spin_ns` before the deadline and then polls
// the clock (vDSO, no system call) until it: the wake-up latency of a halted virtual CPU
// (tens of µs on these VMs, station/README.md "Pacing") is paid before the deadline instead of
// after it, at the cost of `spin_ns` of CPU per period.

#include <cstdint>

namespace microdex::rt {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t NowNs() = 0;                         // monotonic
  virtual void SleepUntilNs(std::int64_t deadline_ns) = 0;  // absolute, monotonic
  virtual std::int64_t RealtimeNs() = 0;                    // for sample stamps
};

class MonotonicClock final : public Clock {
 public:
  explicit MonotonicClock(std::int64_t spin_ns = 0) : spin_ns_(spin_ns) {}
  std::int64_t NowNs() override;
  void SleepUntilNs(std::int64_t deadline_ns) override;
  std::int64_t RealtimeNs() override;
  std::int64_t spin_ns() const { return spin_ns_; }

 private:
  std::int64_t spin_ns_;
};

// A clock that jumps to every deadline (plus an optional fixed lateness): the loop runs as
// fast as the CPU allows and sees perfectly regular periods.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_ns = 1'000'000'000, std::int64_t lateness_ns = 0)
      : now_ns_(start_ns), lateness_ns_(lateness_ns) {}
  std::int64_t NowNs() override { return now_ns_; }
  void SleepUntilNs(std::int64_t deadline_ns) override {
    if (deadline_ns > now_ns_) now_ns_ = deadline_ns + lateness_ns_;
  }
  std::int64_t RealtimeNs() override { return now_ns_ + 1'700'000'000'000'000'000LL; }
  void Advance(std::int64_t ns) { now_ns_ += ns; }

 private:
  std::int64_t now_ns_;
  std::int64_t lateness_ns_;
};

}  // namespace microdex::rt
