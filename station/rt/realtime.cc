#include "station/rt/realtime.h"

#include <dirent.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <iterator>

#include "station/rt/clock.h"

namespace microdex::rt {

bool LockMemory(std::string* why_not) {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    if (why_not) *why_not = std::string("mlockall: ") + std::strerror(errno);
    return false;
  }
  return true;
}

bool MakeThisThreadFifo(int priority, std::string* why_not) {
  sched_param param{};
  param.sched_priority = priority;
  const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (err != 0) {
    if (why_not) *why_not = std::string("SCHED_FIFO: ") + std::strerror(err);
    return false;
  }
  return true;
}

std::vector<int> ThreadIds() {
  std::vector<int> tids;
  DIR* dir = opendir("/proc/self/task");
  if (dir == nullptr) return tids;
  while (const dirent* e = readdir(dir)) {
    if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
    tids.push_back(std::atoi(e->d_name));
  }
  closedir(dir);
  std::sort(tids.begin(), tids.end());
  return tids;
}

std::vector<int> ThreadsStartedSince(const std::vector<int>& before) {
  std::vector<int> started;
  const std::vector<int> now = ThreadIds();
  std::set_difference(now.begin(), now.end(), before.begin(), before.end(),
                      std::back_inserter(started));
  return started;
}

int MakeThreadsFifo(const std::vector<int>& tids, int priority) {
  sched_param param{};
  param.sched_priority = priority;
  int made = 0;
  for (const int tid : tids) {
    // On Linux a thread id names that one thread to sched_setscheduler.
    if (sched_setscheduler(tid, SCHED_FIFO, &param) == 0) ++made;
  }
  return made;
}

std::int64_t MonotonicClock::NowNs() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

void MonotonicClock::SleepUntilNs(std::int64_t deadline_ns) {
  const std::int64_t wake_ns = deadline_ns - spin_ns_;
  timespec ts;
  ts.tv_sec = wake_ns / 1'000'000'000;
  ts.tv_nsec = wake_ns % 1'000'000'000;
  // EINTR: a signal arrived; sleep again until the same absolute time.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
  while (spin_ns_ > 0 && NowNs() < deadline_ns) {
  }
}

std::int64_t MonotonicClock::RealtimeNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace microdex::rt
