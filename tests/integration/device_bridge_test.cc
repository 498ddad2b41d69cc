// The DDS device bridge end to end: a station process with --device dds, a driver in this
// process (station/device_driver.h) that stops sending for 200 ms in the middle, and an
// instructor collecting the station's TaskEvents. The station answers the samples with forces,
// flags the forces of the fault, raises EVENT_DEVICE_FAULT when the samples stop and
// EVENT_DEVICE_OK when they return, and ends normally.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "instructor/instructor.h"
#include "station/device_driver.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
constexpr int kDomain = 83;

TEST(DeviceBridge, DriverFaultIsHeldRaisedAndResumed) {
  const std::string dir = "/tmp/microdex-it-bridge-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  instructor::InstructorOptions options;
  options.dds.profile_file = net::DefaultDdsProfileFile();
  options.dds.domain_id = kDomain;
  options.issuer = "test-console";
  instructor::Instructor console(options);
  std::vector<pid_t> pids;
  pids.push_back(
      testing::Spawn("microdex-station",
                     {"--scene", testing::SourceDir() + "/assets/scenes/needle_tube.yaml",
                      "--station-id", "bridge-1", "--device", "dds", "--duration", "8", "--domain",
                      std::to_string(kDomain), "--score-out", dir + "/bridge-1.json"},
                     dir + "/bridge-1.log"));
  station::DeviceDriverDef def;
  def.station_id = "bridge-1";
  def.duration_s = 3;
  def.fault = station::DriverFault::kStop;
  def.fault_at_s = 1.5;
  def.fault_for_s = 0.2;
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain;
  const std::atomic<bool> stop{false};
  const station::DriverStats s = station::RunDeviceDriver(dds, def, stop);
  ASSERT_TRUE(s.matched) << "the station's bridge was not found (" << dir << ")";
  EXPECT_GT(s.sent, 2500u);
  EXPECT_GT(s.answered, s.sent / 2) << "the station answered most samples";
  EXPECT_GT(s.fault_forces, 100u) << "the stop (200 ms, 10 ms to notice) flagged the forces";
  bool fault = false, ok_after = false;
  ASSERT_TRUE(testing::WaitUntil(
      [&] {
        for (const net::TaskEvent& e : console.TakeEvents()) {
          if (e.header.station_id != "bridge-1") continue;
          if (e.kind == net::TaskEventKind::kDeviceFault) fault = true;
          if (e.kind == net::TaskEventKind::kDeviceOk && fault) ok_after = true;
        }
        return fault && ok_after;
      },
      5s))
      << "fault " << fault << ", ok after it " << ok_after;
  testing::KillAll(pids);
}

}  // namespace
}  // namespace microdex
