// One instructor and four station processes on the loopback profile: all discovered; a cue to
// one station is applied by that station only and acknowledged with its step; a SIGKILLed
// station is reported lost within 2 s and found again when restarted; the stations keep their
// full rate while an instructor process is killed and restarted; SIGTERM stops a station
// within a second, with its departure and final score seen by the instructor.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "instructor/instructor.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
using instructor::Presence;
using testing::Spawn;
using testing::WaitUntil;

constexpr int kDomain = 81;

std::string TmpDir() {
  const std::string dir = "/tmp/microdex-it-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  return dir;
}

class StationInstructorTest : public ::testing::Test {
 protected:
  pid_t StartStation(int i) {
    const std::string id = "st-" + std::to_string(i);
    return Spawn("microdex-station",
                 {"--scene", testing::SourceDir() + "/assets/scenes/needle_tube.yaml",
                  "--station-id", id, "--skill", std::to_string(0.2 * i), "--seed",
                  std::to_string(100 + i), "--trainee", "trainee " + std::to_string(i), "--domain",
                  std::to_string(kDomain), "--score-out", dir_ + "/" + id + ".json"},
                 dir_ + "/" + id + ".log");
  }
  void TearDown() override { testing::KillAll(pids_); }

  std::string dir_ = TmpDir();
  std::vector<pid_t> pids_;
};

bool Alive(const instructor::Instructor& console, const std::string& id) {
  const auto v = console.Station(id);
  return v && v->presence == Presence::kAlive && !v->info.header.session_id.empty();
}

TEST_F(StationInstructorTest, DiscoveryCuesLivelinessRestartAndShutdown) {
  instructor::InstructorOptions options;
  options.dds.profile_file = net::DefaultDdsProfileFile();
  options.dds.domain_id = kDomain;
  options.issuer = "test-console";
  options.receive_inputs = true;  // every DeviceInput step is checked below
  instructor::Instructor console(options);

  pid_t st[5] = {0, 0, 0, 0, 0};
  const auto started = std::chrono::steady_clock::now();
  for (int i = 1; i <= 4; ++i) pids_.push_back(st[i] = StartStation(i));

  // 1. All four discovered, with their scene and modules.
  ASSERT_TRUE(WaitUntil(
      [&] {
        for (int i = 1; i <= 4; ++i) {
          if (!Alive(console, "st-" + std::to_string(i))) return false;
        }
        return true;
      },
      15s))
      << instructor::FormatStationTable(console.Stations(), instructor::MonotonicNowNs());
  const auto st2 = console.Station("st-2");
  EXPECT_EQ(st2->info.modules, (std::vector<std::string>{"needle", "tremor"}));
  EXPECT_EQ(st2->info.trainee, "trainee 2");
  EXPECT_NE(st2->info.scene.find("needle_tube.yaml"), std::string::npos);

  // 2. A cue to st-2 only: applied there, acknowledged with its step, nowhere else.
  const std::uint64_t cue = console.SendCue("st-2", cues::CueKind::kConvergentField, 300);
  std::vector<net::TaskEvent> events;
  std::uint64_t applied_step = 0;
  ASSERT_TRUE(WaitUntil(
      [&] {
        for (auto& e : console.TakeEvents()) events.push_back(e);
        for (const auto& e : events) {
          if (e.kind == net::TaskEventKind::kCueApplied && e.cue_id == cue &&
              e.header.station_id == "st-2") {
            applied_step = e.header.step;
            return true;
          }
        }
        return false;
      },
      5s));
  EXPECT_GT(applied_step, 0u);
  std::this_thread::sleep_for(500ms);
  for (auto& e : console.TakeEvents()) events.push_back(e);
  for (const auto& e : events) {
    if (e.kind == net::TaskEventKind::kCueApplied) {
      EXPECT_EQ(e.header.station_id, "st-2") << "a cue for st-2 was applied elsewhere";
    }
  }
  // The mirrored tool state of st-2 shows the field active, the others not.
  ASSERT_TRUE(WaitUntil(
      [&] {
        const auto v = console.Station("st-2");
        return v->tool.latest && (v->tool.latest->active_cues >> 1) & 1u;
      },
      3s));
  // (The wall is a cue too, on by default: st-1 shows it and nothing else.)
  EXPECT_EQ(console.Station("st-1")->tool.latest->active_cues, cues::CueBit(cues::CueKind::kWall));

  // 3. SIGKILL st-3: reported lost within 2 s by the liveliness path (the 1 s participant
  // lease drops its StationInfo writer), not by the instructor's silence watchdog.
  kill(st[3], SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  waitpid(st[3], nullptr, 0);
  ASSERT_TRUE(WaitUntil([&] { return console.Station("st-3")->presence == Presence::kLost; }, 4s));
  const double lost_after_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  const instructor::LossSignal signal = console.Station("st-3")->lost_by;
  std::printf("st-3 reported lost %.3f s after SIGKILL, by %s\n", lost_after_s,
              instructor::LossSignalName(signal));
  EXPECT_LE(lost_after_s, 2.0);
  EXPECT_TRUE(signal == instructor::LossSignal::kLiveliness ||
              signal == instructor::LossSignal::kNoWriters)
      << "reported by " << instructor::LossSignalName(signal) << ", not by liveliness";
  EXPECT_TRUE(Alive(console, "st-1"));
  EXPECT_TRUE(Alive(console, "st-4"));

  // 4. Restarted st-3 is found again.
  pids_.push_back(st[3] = StartStation(3));
  ASSERT_TRUE(WaitUntil(
      [&] {
        const auto v = console.Station("st-3");
        return v->presence == Presence::kAlive && v->comebacks >= 1;
      },
      10s));

  // 5. An instructor process killed and restarted: the stations keep their rate.
  const auto window_start = std::chrono::steady_clock::now();
  pid_t other = Spawn("microdex-instructor",
                      {"--headless", "--domain", std::to_string(kDomain), "--table-period", "0"},
                      dir_ + "/instructor.log");
  pids_.push_back(other);
  std::this_thread::sleep_for(1500ms);
  kill(other, SIGKILL);
  waitpid(other, nullptr, 0);
  other = Spawn("microdex-instructor",
                {"--headless", "--domain", std::to_string(kDomain), "--table-period", "0"},
                dir_ + "/instructor.log");
  pids_.push_back(other);
  std::this_thread::sleep_for(1500ms);
  kill(other, SIGTERM);
  EXPECT_EQ(testing::WaitExit(other, 3000ms), std::optional<int>(0));
  const double window_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - window_start).count();
  for (int i : {1, 2, 4}) {
    const auto v = console.Station("st-" + std::to_string(i));
    ASSERT_TRUE(v->telemetry.latest);
    EXPECT_EQ(v->telemetry.latest->ring_dropped, 0u) << i;
    EXPECT_EQ(v->inputs_lost, 0u) << "DeviceInput steps missing for st-" << i;
  }

  // 6. SIGTERM: each station leaves within a second, says so, and sends its final score.
  const double run_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  for (int i = 1; i <= 4; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    kill(st[i], SIGTERM);
    const auto rc = testing::WaitExit(st[i], 3000ms);
    const double exit_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(rc, std::optional<int>(0)) << "st-" << i;
    EXPECT_LT(exit_s, 1.0) << "st-" << i << " took " << exit_s << " s to stop";
  }
  ASSERT_TRUE(WaitUntil(
      [&] {
        for (int i = 1; i <= 4; ++i) {
          const auto v = console.Station("st-" + std::to_string(i));
          if (v->presence != Presence::kDeparted) return false;
          if (!v->score.latest || !v->score.latest->is_final) return false;
        }
        return true;
      },
      5s))
      << instructor::FormatStationTable(console.Stations(), instructor::MonotonicNowNs());

  // The stations' own records agree: st-2 applied the cue at the acknowledged step, the others
  // applied none; every station ran at full rate (steps against its wall time) and handed
  // every step to the publisher.
  for (int i = 1; i <= 4; ++i) {
    const std::string json = testing::ReadFile(dir_ + "/st-" + std::to_string(i) + ".json");
    ASSERT_FALSE(json.empty()) << i;
    EXPECT_EQ(testing::JsonNumber(json, "ring_dropped"), 0) << i;
    EXPECT_EQ(testing::JsonNumber(json, "input_write_failed"), 0) << i;
    if (i == 2) {
      EXPECT_EQ(testing::JsonNumber(json, "step"), static_cast<double>(applied_step));
    } else {
      EXPECT_EQ(json.find("\"cue_id\""), std::string::npos) << "st-" << i << " applied a cue";
    }
    if (i != 3) {
      const double steps = testing::JsonNumber(json, "steps");
      // Less one second for the station's start-up (participant creation) before its loop.
      EXPECT_GT(steps, 0.95 * 1000 * (run_s - 1.0)) << "st-" << i << " fell behind 1 kHz";
    }
  }
  std::printf("instructor kill/restart window %.1f s, run %.1f s\n", window_s, run_s);
}

}  // namespace
}  // namespace microdex
