// The DDS device bridge on the haptic thread's side: while a driver (in another thread of this
// process) sends samples at 1 kHz, WaitForSample, Read and WriteForce allocate nothing on the
// calling thread, a sample wakes the wait before its timeout, and the forces and torques reach
// the driver.
#include "station/dds_device.h"

#include <gtest/gtest.h>

#include <thread>

#include "station/device_driver.h"
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

}  // namespace
}  // namespace microdex::station
