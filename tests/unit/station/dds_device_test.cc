// The DDS device bridge on the haptic thread's side: while a driver (in another thread of this
// process) sends samples at 1 kHz, WaitForSample, Read and WriteForce allocate nothing on the
// calling thread, a sample wakes the wait before its timeout, and the forces and torques reach
// the driver.
#include "station/dds_device.h"

#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <thread>
#include <vector>

#include "station/device_driver.h"
#include "station/rt/realtime.h"
#include "tests/support/alloc_counter.h"

namespace microdex::station {
namespace {

constexpr int kDomain = 84;

TEST(DdsDevice, HapticSideNeverAllocatesAndSamplesWakeTheWait) {
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain;
  DdsDevice device(dds, "dds-unit", "session");
  DeviceDriverDef def;
  def.station_id = "dds-unit";
  def.duration_s = 2;
  std::atomic<bool> stop{false};
  DriverStats stats;
  std::thread driver([&] { stats = RunDeviceDriver(dds, def, stop); });
  // Wait for the first sample (discovery), then warm up.
  rt::MonotonicClock clock;
  const std::int64_t give_up = clock.NowNs() + 10'000'000'000LL;
  while (!device.WaitForSample(clock.NowNs() + 5'000'000) && clock.NowNs() < give_up) {
  }
  ASSERT_GT(device.samples_received(), 0u) << "no sample from the driver";
  std::uint64_t step = 0;
  for (int i = 0; i < 100; ++i) {
    device.WaitForSample(clock.NowNs() + 1'500'000);
    device.Read(step++);
    device.WriteForce(Eigen::Vector3d(0.1, 0, 0));
  }
  int woken = 0, valid = 0;
  testing::StartCountingAllocations();
  for (int i = 0; i < 500; ++i) {
    // A sample every millisecond: the wait returns early (true) far more often than not.
    if (device.WaitForSample(clock.NowNs() + 5'000'000)) ++woken;
    const DeviceSample s = device.Read(step++);
    if (s.fault == DeviceFault::kNone) ++valid;
    device.WriteWrench(Eigen::Vector3d(0.2, 0, 0), Eigen::Vector3d(0, 0, 2e-3));
  }
  const std::uint64_t allocations = testing::StopCountingAllocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(woken, 400);
  EXPECT_GT(valid, 400);
  driver.join();
  EXPECT_GT(stats.answered, 300u) << "the forces reached the driver";
  // And the torque with them (identity mapping: the same vector in the device frame).
  EXPECT_NEAR(stats.torque_max_Nm, 2e-3, 1e-15);
  EXPECT_EQ(device.forces_dropped(), 0u);
}

TEST(DdsBridgeTuning, ParsesListsAndNamesBadInput) {
  DdsBridgeTuning t{false, false, false};
  EXPECT_EQ(DdsBridgeTuning::Parse("all", &t), "");
  EXPECT_TRUE(t.shared_memory && t.realtime_threads && t.cpu_latency);
  EXPECT_EQ(t.Name(), "shm,rt,cpu");
  EXPECT_EQ(DdsBridgeTuning::Parse("none", &t), "");
  EXPECT_FALSE(t.shared_memory || t.realtime_threads || t.cpu_latency);
  EXPECT_EQ(t.Name(), "none");
  EXPECT_EQ(DdsBridgeTuning::Parse("rt", &t), "");
  EXPECT_TRUE(!t.shared_memory && t.realtime_threads && !t.cpu_latency);
  EXPECT_EQ(DdsBridgeTuning::Parse("cpu", &t), "");
  EXPECT_EQ(t.Name(), "cpu");
  EXPECT_EQ(DdsBridgeTuning::Parse("rt,shm", &t), "");
  EXPECT_EQ(t.Name(), "shm,rt");
  EXPECT_EQ(t.Apply({}).participant_profile, net::kDeviceBridgeParticipantProfile);
  const std::string why = DdsBridgeTuning::Parse("shm,fast", &t);
  EXPECT_NE(why.find("shm,fast"), std::string::npos) << why;
  EXPECT_NE(why.find("cpu"), std::string::npos) << why;
  EXPECT_EQ(t.Name(), "shm,rt") << "unchanged by bad input";
  EXPECT_NE(DdsBridgeTuning::Parse("", &t), "");
}

// The kernel's PM QoS CPU latency target reads back 0 µs while a request is held and its
// earlier value once it is dropped (root only: /dev/cpu_dma_latency is not readable otherwise).
TEST(DdsBridgeTuning, TheCpuLatencyRequestHoldsTheKernelTargetAtZero) {
  const auto target = []() -> std::optional<std::int32_t> {
    std::FILE* f = std::fopen("/dev/cpu_dma_latency", "rb");
    if (f == nullptr) return std::nullopt;
    std::int32_t v = -1;
    const bool ok = std::fread(&v, sizeof v, 1, f) == 1;
    std::fclose(f);
    return ok ? std::optional<std::int32_t>(v) : std::nullopt;
  };
  const std::optional<std::int32_t> before = target();
  if (!before) GTEST_SKIP() << "/dev/cpu_dma_latency not readable (not root)";
  {
    CpuLatencyRequest request;
    ASSERT_TRUE(request.held()) << request.why_not();
    EXPECT_EQ(target(), 0);
  }
  EXPECT_EQ(target(), before) << "the request is dropped with the object";
}

TEST(RealTime, ThreadsStartedSinceFindsTheNewThreadAndRaisesIt) {
  const std::vector<int> before = rt::ThreadIds();
  ASSERT_FALSE(before.empty());
  std::atomic<bool> release{false};
  std::atomic<int> tid{0};
  std::thread t([&] {
    tid = static_cast<int>(gettid());
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  while (tid == 0) std::this_thread::yield();
  const std::vector<int> started = rt::ThreadsStartedSince(before);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0], tid.load());
  if (rt::MakeThreadsFifo(started, 10) == 1) {
    EXPECT_EQ(sched_getscheduler(tid), SCHED_FIFO);
    sched_param p{};
    ASSERT_EQ(sched_getparam(tid, &p), 0);
    EXPECT_EQ(p.sched_priority, 10);
  } else {
    EXPECT_EQ(sched_getscheduler(tid), SCHED_OTHER) << "not permitted: left as it was";
  }
  release = true;
  t.join();
}

// The participant's own threads: how many of this process's threads run SCHED_FIFO `priority`.
int ThreadsAtFifo(int priority) {
  int n = 0;
  for (const int tid : rt::ThreadIds()) {
    sched_param p{};
    if (sched_getscheduler(tid) == SCHED_FIFO && sched_getparam(tid, &p) == 0 &&
        p.sched_priority == priority) {
      ++n;
    }
  }
  return n;
}

TEST(DdsDevice, TuningChoosesTheParticipantAndRaisesItsThreads) {
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain + 1;
  // (Fast DDS's process-wide threads started with an earlier participant may run there too.)
  const int before = ThreadsAtFifo(DdsDevice::kDdsThreadPriority);
  {
    DdsDevice plain(dds, "dds-plain", "session", {}, {}, DdsBridgeTuning{false, false});
    EXPECT_EQ(plain.participant_profile(), net::kParticipantProfile);
    EXPECT_EQ(plain.dds_threads_realtime(), 0);
    EXPECT_EQ(ThreadsAtFifo(DdsDevice::kDdsThreadPriority), before);
  }
  const int after_plain = ThreadsAtFifo(DdsDevice::kDdsThreadPriority);
  DdsDevice tuned(dds, "dds-tuned", "session", {}, {}, DdsBridgeTuning{});
  EXPECT_EQ(tuned.participant_profile(), net::kDeviceBridgeParticipantProfile);
  // Privilege permitting, the threads Fast DDS started for it (at least its receive and event
  // threads) and only those run just below the haptic thread.
  std::string why;
  std::thread probe([&] { rt::MakeThisThreadFifo(1, &why); });
  probe.join();
  if (why.empty()) {
    EXPECT_GE(tuned.dds_threads_realtime(), 2);
    EXPECT_EQ(ThreadsAtFifo(DdsDevice::kDdsThreadPriority),
              after_plain + tuned.dds_threads_realtime());
  } else {
    EXPECT_EQ(tuned.dds_threads_realtime(), 0) << why;
  }
}

}  // namespace
}  // namespace microdex::station
