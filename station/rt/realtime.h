#pragma once
// Real-time setup for the haptic thread: memory locked (mlockall) and SCHED_FIFO when the
// process is permitted; otherwise the loop still runs on absolute deadlines, and the caller
// logs one line saying why it is not real-time.

#include <string>
#include <vector>

namespace microdex::rt {

struct RealtimeStatus {
  bool memory_locked = false;
  bool fifo = false;
  std::string why_not;  // empty when both succeeded
};

// Locks current and future pages. Call once from main, before the threads start.
bool LockMemory(std::string* why_not);
// Gives the calling thread SCHED_FIFO at `priority` (1..99).
bool MakeThisThreadFifo(int priority, std::string* why_not);

// The ids of this process's threads (/proc/self/task), ascending. The threads a library
// creates inside a call are those listed after it and not before (ThreadsStartedSince).
std::vector<int> ThreadIds();
std::vector<int> ThreadsStartedSince(const std::vector<int>& before);
// Gives each of the threads SCHED_FIFO at `priority`; returns how many took it (0 without the
// privilege; a thread that has ended meanwhile is skipped).
int MakeThreadsFifo(const std::vector<int>& tids, int priority);

}  // namespace microdex::rt
