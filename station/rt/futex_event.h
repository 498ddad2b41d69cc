#pragma once
// A counter one thread bumps and another waits on, without a lock: the producer increments it
// and wakes the waiter (FUTEX_WAKE: one non-blocking system call, no allocation); the consumer
// reads the count, does its work, and waits for the count to change (FUTEX_WAIT with a
// timeout). Used by the DDS device bridge: the DDS listener thread (producer) wakes the haptic
// thread (consumer) when a sample arrives; the haptic thread (producer) wakes the bridge's
// publisher thread (consumer) when a force is ready. Linux only.

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <ctime>

namespace microdex::rt {

class FutexEvent {
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));

 public:
  // Producer: one more event, and wake the waiter if any.
  void Notify() {
    count_.fetch_add(1, std::memory_order_release);
    syscall(SYS_futex, Word(), FUTEX_WAKE_PRIVATE, 1, nullptr, nullptr, 0);
  }
  // Consumer: the current count (read it before looking for work).
  std::uint32_t count() const { return count_.load(std::memory_order_acquire); }
  // Consumer: returns when the count differs from `seen` or after timeout_ns (spurious
  // returns are possible: compare count() again).
  void WaitWhile(std::uint32_t seen, std::int64_t timeout_ns) {
    if (timeout_ns <= 0 || count() != seen) return;
    timespec ts{static_cast<time_t>(timeout_ns / 1'000'000'000),
                static_cast<long>(timeout_ns % 1'000'000'000)};
    syscall(SYS_futex, Word(), FUTEX_WAIT_PRIVATE, seen, &ts, nullptr, 0);
  }

 private:
  // The atomic's object representation is the 32-bit word the kernel compares.
  std::uint32_t* Word() { return reinterpret_cast<std::uint32_t*>(&count_); }
  std::atomic<std::uint32_t> count_{0};
};

}  // namespace microdex::rt
