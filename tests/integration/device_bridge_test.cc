// The DDS device bridge end to end: a station process with --device dds, a driver in this
// process (station/device_driver.h) that stops sending for 200 ms in the middle, and an
// instructor collecting the station's TaskEvents. The station answers the samples with forces,
// flags the forces of the fault, raises EVENT_DEVICE_FAULT when the samples stop and
// EVENT_DEVICE_OK when they return, and ends normally. Hostile samples (invalid device samples
// on the bridge, invalid cue commands) are counted in the station's Telemetry.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "common/net/dds_context.h"
#include "common/net/topics.h"
#include "device_inputPubSubTypes.h"
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

// A station on the bridge without a driver; this process writes device samples to it (valid
// ones, then ones with a zero quaternion, a gripper of 5 or a NaN position) and the console
// sends it cues (a NaN parameter, one beyond the kind's limits, and a valid one). The station
// counts exactly the invalid ones in its Telemetry, which the console mirrors.
TEST(DeviceBridge, HostileSamplesAreCountedInTheStationsTelemetry) {
  const std::string dir = "/tmp/microdex-it-bridge-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  instructor::InstructorOptions options;
  options.dds.profile_file = net::DefaultDdsProfileFile();
  options.dds.domain_id = kDomain;
  options.issuer = "test-console";
  instructor::Instructor console(options);
  const std::vector<pid_t> pids = {testing::Spawn(
      "microdex-station",
      {"--scene", testing::SourceDir() + "/assets/scenes/needle_tube.yaml", "--station-id",
       "bridge-2", "--device", "dds", "--duration", "20", "--domain", std::to_string(kDomain)},
      dir + "/bridge-2.log")};
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain;
  net::DdsContext driver(dds);
  auto* writer = driver.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceSampleTopic);
  ASSERT_TRUE(testing::WaitUntil(
      [&] {
        eprosima::fastdds::dds::PublicationMatchedStatus st;
        writer->get_publication_matched_status(st);
        const auto v = console.Station("bridge-2");
        return st.current_count > 0 && v && v->telemetry.latest;
      },
      15000ms))
      << "the station's bridge or its telemetry was not found (" << dir << ")";

  msg::DeviceInput m;
  m.station_id("bridge-2");
  m.session_id("driver");
  m.q_WT({1, 0, 0, 0});
  constexpr int kValid = 5, kZeroQ = 10, kGrip = 5, kNaN = 10;
  std::uint64_t step = 0;
  const auto send = [&](int n) {
    for (int i = 0; i < n; ++i) {
      m.step(++step);
      ASSERT_TRUE(writer->write(&m));
      std::this_thread::sleep_for(10ms);  // the bridge's reader keeps the latest only
    }
  };
  send(kValid);
  m.q_WT({0, 0, 0, 0});
  send(kZeroQ);
  m.q_WT({1, 0, 0, 0});
  m.gripper(5);
  send(kGrip);
  m.gripper(0);
  m.p_WT({std::nan(""), 0, 0});
  send(kNaN);
  console.SendCue("bridge-2", cues::CueKind::kConvergentField, std::nan(""));
  console.SendCue("bridge-2", cues::CueKind::kConvergentField, 1e9);
  console.SendCue("bridge-2", cues::CueKind::kConvergentField, 300);

  int applied = 0, rejected = 0;
  const bool counted = testing::WaitUntil(
      [&] {
        const auto v = console.Station("bridge-2");
        applied = rejected = 0;
        for (const net::TaskEvent& e : v->events) {
          if (e.kind == net::TaskEventKind::kCueApplied) ++applied;
          if (e.kind == net::TaskEventKind::kCueRejected) ++rejected;
        }
        return v->telemetry.latest &&
               v->telemetry.latest->device_samples_invalid == kZeroQ + kGrip + kNaN &&
               v->telemetry.latest->cues_invalid == 2 && applied + rejected == 3;
      },
      10000ms);
  const auto v = console.Station("bridge-2");
  ASSERT_TRUE(v && v->telemetry.latest);
  EXPECT_TRUE(counted) << "device samples invalid " << v->telemetry.latest->device_samples_invalid
                       << ", cues invalid " << v->telemetry.latest->cues_invalid;
  EXPECT_EQ(rejected, 2);
  EXPECT_EQ(applied, 1) << "the valid cue (the control)";
  // The instructor itself refused nothing: these samples are valid DDS samples of the station.
  EXPECT_EQ(console.Rejected().total, 0u) << instructor::FormatRejected(console.Rejected());
  testing::KillAll(pids);
}

}  // namespace
}  // namespace microdex
