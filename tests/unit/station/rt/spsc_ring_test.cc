// The SPSC ring: FIFO order, full and empty at the right moments, wrap-around, and a
// two-thread run (producer and consumer as in the station) that loses and reorders nothing.
// Run under the tsan preset to check the memory ordering.
#include "station/rt/spsc_ring.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace microdex::rt {
namespace {

TEST(SpscRing, FifoFullEmptyAndWrap) {
  SpscRing<int> ring(4);
  int out = -1;
  EXPECT_FALSE(ring.TryPop(out));
  for (int round = 0; round < 5; ++round) {  // wraps the indices several times
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.TryPush(round * 10 + i));
    EXPECT_FALSE(ring.TryPush(99)) << "a full ring accepted an item";
    EXPECT_EQ(ring.size(), 4u);
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(ring.TryPop(out));
      EXPECT_EQ(out, round * 10 + i);
    }
    EXPECT_FALSE(ring.TryPop(out));
  }
}

struct Item {
  std::uint64_t seq;
  std::uint64_t check;  // seq * constant: a torn copy would not match
};

TEST(SpscRing, TwoThreadsLoseNothing) {
  constexpr std::uint64_t kItems = 300'000;
  constexpr std::uint64_t kMul = 0x9E3779B97F4A7C15ULL;
  SpscRing<Item> ring(64);
  std::uint64_t dropped = 0;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems;) {
      if (ring.TryPush({i, i * kMul})) {
        ++i;
      } else {
        ++dropped;  // full: retry (the station instead counts a drop and moves on)
        std::this_thread::yield();
      }
    }
  });
  std::uint64_t expected = 0;
  bool ok = true;
  while (expected < kItems) {
    Item item;
    if (ring.TryPop(item)) {
      if (item.seq != expected || item.check != item.seq * kMul) ok = false;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_TRUE(ok) << "an item arrived out of order or torn";
  EXPECT_EQ(expected, kItems);
  Item extra;
  EXPECT_FALSE(ring.TryPop(extra));
}

}  // namespace
}  // namespace microdex::rt
