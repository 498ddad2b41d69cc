// When the console forwards a station's state to its page (FrameForwarder,
// instructor/console_server.h): fresh, at about the console's rate, and never stuck on a
// skipped state.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "instructor/console_server.h"

namespace microdex::instructor {
namespace {

constexpr std::int64_t kMs = 1'000'000;

struct Sent {
  std::int64_t at_ns;
  std::int64_t age_ns;  // since the state arrived
};

// A station mirroring at mirror_hz (arrivals with the given jitter pattern), polled every
// poll_ms for duration_ms: what the forwarder sends.
std::vector<Sent> Simulate(double rate_hz, double mirror_hz, std::int64_t poll_ms,
                           std::int64_t duration_ms, std::int64_t jitter_ms = 0,
                           std::int64_t quiet_after_ms = 1'000'000) {
  FrameForwarder f(rate_hz);
  std::vector<Sent> sent;
  std::uint64_t count = 0;
  std::int64_t received_ns = 0;
  const auto period_ns = static_cast<std::int64_t>(1e9 / mirror_hz);
  std::int64_t next_arrival_ns = 5 * kMs;
  for (std::int64_t now = 0; now <= duration_ms * kMs; now += poll_ms * kMs) {
    while (next_arrival_ns <= now && next_arrival_ns <= quiet_after_ms * kMs) {
      ++count;
      received_ns = next_arrival_ns;
      // Alternating early and late arrivals around the nominal period.
      next_arrival_ns += period_ns + ((count % 2) != 0 ? jitter_ms : -jitter_ms) * kMs;
    }
    if (f.Due(count, received_ns, now)) sent.push_back({now, now - received_ns});
  }
  return sent;
}

TEST(FrameForwarder, SendsNothingBeforeTheFirstState) {
  FrameForwarder f(30);
  EXPECT_FALSE(f.Due(0, 0, 0));
  EXPECT_FALSE(f.Due(0, 0, 100 * kMs));
  EXPECT_TRUE(f.Due(1, 100 * kMs, 101 * kMs));
  EXPECT_FALSE(f.Due(1, 100 * kMs, 500 * kMs));  // the same state is not sent twice
}

// A 60 Hz mirror forwarded at 30 Hz: every state sent is at most a poll period old, and
// about every other one goes.
TEST(FrameForwarder, SixtyHertzMirrorGoesOutAtThirtyHertzFresh) {
  for (const std::int64_t jitter : {0, 2, 4}) {
    SCOPED_TRACE(jitter);
    const std::vector<Sent> sent = Simulate(30, 60, 2, 2000, jitter);
    EXPECT_GE(sent.size(), 58U);
    EXPECT_LE(sent.size(), 61U);
    for (const Sent& s : sent) EXPECT_LT(s.age_ns, 2 * kMs);
  }
}

// A mirror at or below the console's rate: every state goes, each at once.
TEST(FrameForwarder, SlowerMirrorsGoOutWhole) {
  for (const double mirror : {30.0, 20.0, 5.0}) {
    SCOPED_TRACE(mirror);
    const std::vector<Sent> sent = Simulate(30, mirror, 2, 2000, 1);
    EXPECT_NEAR(static_cast<double>(sent.size()), 2.0 * mirror, 1.0);
    for (const Sent& s : sent) EXPECT_LT(s.age_ns, 2 * kMs);
  }
}

// A station that goes quiet right after a skipped state: that state is sent a period later,
// so the page ends on the station's last state.
TEST(FrameForwarder, LastStateOfAQuietStationIsSent) {
  // 60 Hz arrivals at 5, 21.7, 38.3, ... ms; quiet after 23 ms: the state of 21.7 ms was
  // skipped (16.7 ms after the one sent).
  const std::vector<Sent> sent = Simulate(30, 60, 2, 200, 0, 23);
  ASSERT_EQ(sent.size(), 2U);
  EXPECT_EQ(sent[0].at_ns, 6 * kMs);
  EXPECT_GE(sent[1].age_ns, 33 * kMs);  // held one console period,
  EXPECT_LT(sent[1].age_ns, 36 * kMs);  // then sent at the next poll
}

// A very fast mirror (a station set to 1 kHz) still goes out at about the console's rate.
TEST(FrameForwarder, FastMirrorIsRateLimited) {
  const std::vector<Sent> sent = Simulate(30, 1000, 2, 3000);
  EXPECT_GE(sent.size(), 100U);  // 3 s at one per 0.8 period ≥ 26.7 ms, polled every 2 ms
  EXPECT_LE(sent.size(), 113U);
  for (std::size_t i = 1; i < sent.size(); ++i) {
    EXPECT_GE(sent[i].at_ns - sent[i - 1].at_ns, static_cast<std::int64_t>(0.8e9 / 30));
  }
}

}  // namespace
}  // namespace microdex::instructor
