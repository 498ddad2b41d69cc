// The triple buffer: the consumer sees nothing before the first publication, then always the
// latest published value, never a torn one, and the producer never waits. The two-thread run
// is the one the tsan preset checks.
#include "station/rt/triple_buffer.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

namespace microdex::rt {
namespace {

TEST(TripleBuffer, LatestWinsAndNothingBeforeThePublication) {
  TripleBuffer<int> b;
  EXPECT_FALSE(b.Update());
  b.back() = 1;
  b.Publish();
  b.back() = 2;
  b.Publish();  // overwrites the unread 1
  ASSERT_TRUE(b.Update());
  EXPECT_EQ(b.front(), 2);
  EXPECT_FALSE(b.Update()) << "no new value was published";
  EXPECT_EQ(b.front(), 2);
  for (int i = 3; i < 20; ++i) {  // the slots rotate through every position
    b.back() = i;
    b.Publish();
    ASSERT_TRUE(b.Update());
    EXPECT_EQ(b.front(), i);
  }
}

// A large item whose words must all agree: a torn copy (reader and writer on one slot) shows.
struct Frame {
  std::uint64_t seq;
  std::array<std::uint64_t, 512> words;
};

TEST(TripleBuffer, TwoThreadsSeeWholeIncreasingValues) {
  constexpr std::uint64_t kFrames = 20'000;
  TripleBuffer<Frame> b;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t i = 1; i <= kFrames; ++i) {
      Frame& f = b.back();
      f.seq = i;
      for (auto& w : f.words) w = i * 0x9E3779B97F4A7C15ULL;
      b.Publish();
    }
    done = true;
  });
  std::uint64_t last = 0, taken = 0;
  bool whole = true, increasing = true;
  for (;;) {
    const bool finished = done.load();
    if (b.Update()) {
      const Frame& f = b.front();
      for (auto w : f.words) whole = whole && w == f.seq * 0x9E3779B97F4A7C15ULL;
      increasing = increasing && f.seq > last;
      last = f.seq;
      ++taken;
    } else if (finished) {
      break;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_TRUE(whole) << "a frame was read while being written";
  EXPECT_TRUE(increasing) << "an older frame followed a newer one";
  EXPECT_EQ(last, kFrames) << "the last published frame was not seen";
  EXPECT_GT(taken, 0u);
}

}  // namespace
}  // namespace microdex::rt
