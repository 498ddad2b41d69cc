// MonotonicClock's pacing: SleepUntilNs never returns before the deadline, with or without the
// spin tail, and with the tail the thread is not asleep at the deadline (it polls the clock
// for the last spin_ns).
#include "station/rt/clock.h"

#include <gtest/gtest.h>
#include <time.h>

#include <cstdint>

namespace microdex::rt {
namespace {

std::int64_t ThreadCpuNs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

TEST(MonotonicClock, NeverWakesBeforeTheDeadlineWithOrWithoutTheSpinTail) {
  for (const std::int64_t spin_ns : {0LL, 50'000LL, 200'000LL}) {
    MonotonicClock clock(spin_ns);
    EXPECT_EQ(clock.spin_ns(), spin_ns);
    std::int64_t deadline = clock.NowNs();
    for (int i = 0; i < 200; ++i) {
      deadline += 1'000'000;
      clock.SleepUntilNs(deadline);
      ASSERT_GE(clock.NowNs(), deadline) << "spin " << spin_ns << " ns, tick " << i;
    }
  }
}

TEST(MonotonicClock, TheSpinTailPollsForItsLength) {
  // 100 periods of 1 ms: sleeping to the deadline costs little CPU; a 400 µs tail costs about
  // 40 % of the time (the thread polls from 400 µs before each deadline, or from its wake-up).
  auto cpu_fraction = [](std::int64_t spin_ns) {
    MonotonicClock clock(spin_ns);
    const std::int64_t cpu0 = ThreadCpuNs();
    const std::int64_t t0 = clock.NowNs();
    std::int64_t deadline = t0;
    for (int i = 0; i < 100; ++i) clock.SleepUntilNs(deadline += 1'000'000);
    return static_cast<double>(ThreadCpuNs() - cpu0) / static_cast<double>(clock.NowNs() - t0);
  };
  const double sleeping = cpu_fraction(0);
  const double spinning = cpu_fraction(400'000);
  EXPECT_LT(sleeping, 0.05);
  // At most the tail (a preempted thread polls less, never more).
  EXPECT_GT(spinning, 0.1);
  EXPECT_LT(spinning, 0.5);
}

}  // namespace
}  // namespace microdex::rt
