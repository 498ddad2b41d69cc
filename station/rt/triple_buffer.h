#pragma once
// A latest-value handoff of one large, trivially copyable item between two threads (a triple
// buffer): the producer fills its back slot and publishes it; the consumer takes the newest
// published slot when it wants one. Neither side ever waits, and neither copies the item
// through the handoff: three slots rotate between "back" (producer's), "middle" (the latest
// published) and "front" (consumer's). Older unread values are overwritten: only the latest
// matters (the mirrored thread and tissue states). Storage is allocated once at construction.
//
// Instances in the station (snapshot.h, LargeFrames):
//   thread, tissue: producer = haptic thread (every mirror period), consumer = publisher thread
//
// Memory order: Publish() swaps the back slot into the middle with release (the slot's
// contents happen before the swap); Update() swaps the middle out with acquire before the
// consumer reads it. The "fresh" bit in the middle index tells the consumer there is a slot it
// has not taken yet.

#include <atomic>
#include <cstdint>
#include <memory>
#include <type_traits>

namespace microdex::rt {

template <class T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "frames are plain data");

 public:
  TripleBuffer() : slots_(std::make_unique<T[]>(3)) {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // Producer thread only: the slot to fill (not visible to the consumer until Publish()).
  T& back() { return slots_[back_]; }
  // Producer thread only: makes back() the latest value; the producer gets a free slot.
  void Publish() {
    const std::uint32_t old_middle = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = old_middle & kIndexMask;
  }

  // Consumer thread only: takes the latest published value into front() when one was
  // published since the last call; true when front() changed.
  bool Update() {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    const std::uint32_t old_middle = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old_middle & kIndexMask;
    return true;
  }
  // Consumer thread only: the value taken by the last successful Update().
  const T& front() const { return slots_[front_]; }

 private:
  static constexpr std::uint32_t kFresh = 4;
  static constexpr std::uint32_t kIndexMask = 3;
  std::unique_ptr<T[]> slots_;
  std::uint32_t back_ = 0;   // producer's
  std::uint32_t front_ = 1;  // consumer's
  std::atomic<std::uint32_t> middle_{2};
};

}  // namespace microdex::rt
