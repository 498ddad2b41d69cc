#pragma once
// A bounded single-producer/single-consumer ring of trivially copyable items: the handoff
// between the haptic thread and the publisher thread. Wait-free on both sides: TryPush fails
// when the ring is full (the producer counts the drop and never waits), TryPop fails when it
// is empty. Storage is sized once at construction; nothing allocates afterwards.
//
// Instances in the station (each names its threads where it is declared):
//   snapshots: producer = haptic thread, consumer = publisher thread
//   cues:      producer = publisher thread, consumer = haptic thread
//
// Memory order: the producer writes the slot, then publishes head with release; the consumer
// reads head with acquire before reading the slot, and publishes tail with release after it;
// the producer reads tail with acquire before reusing a slot.

#include <atomic>
#include <cstddef>
#include <memory>
#include <type_traits>

#include "common/base/check.h"

namespace microdex::rt {

template <class T>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "ring items are copied as plain data");

 public:
  // capacity: a power of two >= 2.
  explicit SpscRing(std::size_t capacity)
      : capacity_(capacity), mask_(capacity - 1), slots_(new T[capacity]) {
    MICRODEX_CHECK(capacity >= 2 && (capacity & (capacity - 1)) == 0);
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  // Producer thread only. False when full.
  bool TryPush(const T& item) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - cached_tail_ == capacity_) {
      cached_tail_ = tail_.load(std::memory_order_acquire);
      if (head - cached_tail_ == capacity_) return false;
    }
    slots_[head & mask_] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer thread only. False when empty.
  bool TryPop(T& item) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == cached_head_) {
      cached_head_ = head_.load(std::memory_order_acquire);
      if (tail == cached_head_) return false;
    }
    item = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  std::size_t capacity() const { return capacity_; }
  // Approximate (exact when both threads are quiet).
  std::size_t size() const {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  static constexpr std::size_t kCacheLine = 64;
  const std::size_t capacity_;
  const std::size_t mask_;
  std::unique_ptr<T[]> slots_;
  // Producer side: head_ written, cached_tail_ private.
  alignas(kCacheLine) std::atomic<std::size_t> head_{0};
  std::size_t cached_tail_ = 0;
  // Consumer side: tail_ written, cached_head_ private.
  alignas(kCacheLine) std::atomic<std::size_t> tail_{0};
  std::size_t cached_head_ = 0;
};

}  // namespace microdex::rt
