// The recording holds the topics only a recorder reads: CueOverlay (every station) and the DDS
// device bridge's DeviceForce (a station with --device dds driven by a driver in this
// process). Each sample decodes; the forces are finite and answer the driver's samples.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <map>
#include <thread>

#include "common/record/recorded_topics.h"
#include "common/record/session_reader.h"
#include "cue_overlayPubSubTypes.h"
#include "device_forcePubSubTypes.h"
#include "instructor/instructor.h"
#include "instructor/recorded_sample.h"
#include "station/device_driver.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
constexpr int kDomain = 143;

TEST(RecordTopics, CueOverlayAndDeviceForceAreRecorded) {
  std::string dir = "/tmp/microdex-it-record-topics-XXXXXX";
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  const std::string file = dir + "/session.db";
  std::vector<pid_t> pids;
  {
    instructor::InstructorOptions options;
    options.dds.profile_file = net::DefaultDdsProfileFile();
    options.dds.domain_id = kDomain;
    options.record_file = file;
    instructor::Instructor console(options);
    pids.push_back(testing::Spawn(
        "microdex-station",
        {"--scene", testing::SourceDir() + "/assets/scenes/needle_tube.yaml", "--station-id",
         "bridge-r", "--device", "dds", "--duration", "4", "--domain", std::to_string(kDomain),
         "--cue", "visual_path", "--no-realtime"},
        dir + "/station.log"));
    station::DeviceDriverDef def;
    def.station_id = "bridge-r";
    def.duration_s = 2;
    net::DdsOptions dds;
    dds.profile_file = net::DefaultDdsProfileFile();
    dds.domain_id = kDomain;
    const std::atomic<bool> stop{false};
    const station::DriverStats s = station::RunDeviceDriver(dds, def, stop);
    ASSERT_TRUE(s.matched) << testing::ReadFile(dir + "/station.log");
    const auto status = testing::WaitExit(pids[0], 30s);
    ASSERT_TRUE(status.has_value());
    EXPECT_EQ(*status, 0) << testing::ReadFile(dir + "/station.log");
    std::this_thread::sleep_for(300ms);
    console.FlushRecording();
  }
  testing::KillAll(pids);

  record::SessionReader reader(file);
  std::map<int, int> count;
  int finite = 0, with_path = 0, unanswered_after_first = 0;
  bool answered = false;
  reader.ForEach({}, [&](const record::MessageView& m) {
    ++count[m.topic];
    if (m.topic == static_cast<int>(record::TopicIndex::kDeviceForce)) {
      msg::DeviceForce f;
      EXPECT_TRUE(instructor::DecodeSample<msg::DeviceForcePubSubType>(m.cdr, f));
      EXPECT_EQ(m.station, "bridge-r");
      finite += std::isfinite(f.f_D()[0]) && std::isfinite(f.f_D()[1]) && std::isfinite(f.f_D()[2])
                    ? 1
                    : 0;
      // The station ticks before the driver's first sample arrives: those forces echo sample
      // 0 (none read yet), and the recorder may have matched the force writer just before.
      // Once a force answers a sample, every later one does.
      if (f.sample_step() > 0) {
        answered = true;
      } else if (answered) {
        ++unanswered_after_first;
      }
    } else if (m.topic == static_cast<int>(record::TopicIndex::kCueOverlay)) {
      msg::CueOverlay o;
      EXPECT_TRUE(instructor::DecodeSample<msg::CueOverlayPubSubType>(m.cdr, o));
      with_path += o.polylines().empty() ? 0 : 1;
    }
    return true;
  });
  EXPECT_TRUE(reader.problems().empty());
  const int forces = count[static_cast<int>(record::TopicIndex::kDeviceForce)];
  const int overlays = count[static_cast<int>(record::TopicIndex::kCueOverlay)];
  // A force every step of the station's 4 s at 1 kHz (best-effort: a few may be lost).
  EXPECT_GT(forces, 1000);
  EXPECT_EQ(finite, forces);
  EXPECT_TRUE(answered);
  EXPECT_EQ(unanswered_after_first, 0);
  EXPECT_GT(overlays, 60);  // 4 s at 60 Hz, best-effort
  EXPECT_GT(with_path, overlays / 2);
  std::printf("recorded %d DeviceForce and %d CueOverlay samples (%d with the path drawn)\n",
              forces, overlays, with_path);
}

}  // namespace
}  // namespace microdex
