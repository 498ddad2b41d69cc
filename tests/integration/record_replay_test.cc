// Recording and replay, with real processes on the loopback profile:
// - every training scene recorded by `microdex-instructor --record` (a cue to all stations
//   included) re-simulates with every step's state hash matching (`microdex-replay
//   --resimulate` exits 0); one device sample altered in the file is reported at its station
//   and step (exit 1); the replay over DDS is mirrored by an instructor as if live; the CSV
//   export has one row per recorded sample;
// - a recorder killed with SIGKILL leaves a file that opens and holds the session up to at
//   most 200 ms before the kill, with no DeviceInput missing before that.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "common/record/recorded_topics.h"
#include "common/record/session_reader.h"
#include "device_inputPubSubTypes.h"
#include "instructor/instructor.h"
#include "instructor/recorded_sample.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
using testing::Spawn;
using testing::WaitExit;

constexpr int kDomain = 131;
constexpr int kReplayDomain = 132;

// The training scenes recorded together in one session (the needle through tissue and the
// bimanual thread scene in a session of their own, below: two FEM/thread stations more would
// load the two cores beyond what the paced stations of the first session keep up with).
const char* const kTrainingScenes[] = {"tremor_hold",   "loop_along_wire", "needle_along_tube",
                                       "grasp",         "nylon_loop",      "knot_topology",
                                       "knot_placement"};
const char* const kHeavyScenes[] = {"needle_through_tissue", "thread_two_hands"};

std::string TmpDir() {
  std::string dir = "/tmp/microdex-record-XXXXXX";
  return mkdtemp(dir.data()) ? dir : "/tmp";
}

std::string ReadFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::int64_t RealtimeNowNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// Runs microdex-replay with args to completion; its exit status, output in `log`.
int RunReplay(const std::vector<std::string>& args, const std::string& log) {
  std::remove(log.c_str());
  const pid_t pid = Spawn("microdex-replay", args, log);
  const auto status = WaitExit(pid, 120s);
  if (!status) {
    testing::KillAll({pid});
    return -1;
  }
  return *status;
}

// Moves the tool x of station's DeviceInput at `step` by 1 nm, in place in the file.
bool AlterDeviceInput(const std::string& file, const std::string& station, std::uint64_t step) {
  sqlite3* db = nullptr;
  if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) return false;
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db,
                     "SELECT id, data FROM messages WHERE station = ?1 AND step = ?2 AND "
                     "topic_id = (SELECT id FROM topics WHERE name = 'microdex/device_input')",
                     -1, &st, nullptr);
  sqlite3_bind_text(st, 1, station.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int64(st, 2, static_cast<sqlite3_int64>(step));
  bool ok = false;
  if (sqlite3_step(st) == SQLITE_ROW) {
    const sqlite3_int64 id = sqlite3_column_int64(st, 0);
    const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(st, 1));
    std::vector<std::uint8_t> cdr(data, data + sqlite3_column_bytes(st, 1));
    msg::DeviceInput m;
    if (instructor::DecodeSample<msg::DeviceInputPubSubType>(cdr, m)) {
      m.p_WT()[0] += 1e-9;
      msg::DeviceInputPubSubType type;
      eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&m)());
      if (type.serialize(&m, &payload)) {
        sqlite3_stmt* up = nullptr;
        sqlite3_prepare_v2(db, "UPDATE messages SET data = ?1 WHERE id = ?2", -1, &up, nullptr);
        sqlite3_bind_blob(up, 1, payload.data, static_cast<int>(payload.length), SQLITE_TRANSIENT);
        sqlite3_bind_int64(up, 2, id);
        ok = sqlite3_step(up) == SQLITE_DONE && sqlite3_changes(db) == 1;
        sqlite3_finalize(up);
      }
    }
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return ok;
}

// The re-simulation log's line for station `id`: its steps re-simulated, every one's hash
// matched.
void ExpectEveryStepHashMatched(const std::string& out, const char* id) {
  const auto at = out.find(std::string("station ") + id + " ");
  ASSERT_NE(at, std::string::npos) << id << "\n" << out;
  const std::string line = out.substr(at, out.find('\n', at) - at);
  unsigned long long steps = 0, hashes = 0;
  const auto n = line.find("): ");
  ASSERT_EQ(std::sscanf(line.c_str() + n + 3, "%llu steps re-simulated, %llu step hashes", &steps,
                        &hashes),
            2)
      << line;
  EXPECT_GE(steps, 3000u) << line;  // 4000 stepped; the last ones may leave with the station
  EXPECT_EQ(hashes, steps) << line;
}

class RecordReplayTest : public ::testing::Test {
 protected:
  void TearDown() override { testing::KillAll(pids_); }
  std::string dir_ = TmpDir();
  std::vector<pid_t> pids_;
};

TEST_F(RecordReplayTest, EveryTrainingSceneReSimulatesAndAnAlteredSampleIsFound) {
  const std::string file = dir_ + "/session.db";
  const pid_t console =
      Spawn("microdex-instructor",
            {"--headless", "--table-period", "0", "--domain", std::to_string(kDomain), "--record",
             file, "--cue", "all:convergent:150@1.5", "--cue", "all:tremor:3@2.5", "--cue",
             "all:tremor:off@3.2"},
            dir_ + "/instructor.log");
  pids_.push_back(console);
  // Paced stations for 4 simulated seconds each (all of them at once), each waiting for the
  // recorder's DeviceInput reader before its first step.
  std::vector<pid_t> stations;
  for (std::size_t i = 0; i < std::size(kTrainingScenes); ++i) {
    const std::string id = kTrainingScenes[i];
    stations.push_back(
        Spawn("microdex-station",
              {"--scene", "assets/scenes/" + id + ".yaml", "--station-id", id, "--seed",
               std::to_string(40 + i), "--skill", "0.4", "--duration", "4", "--no-realtime",
               "--domain", std::to_string(kDomain), "--wait-for-recorder", "20"},
              dir_ + "/" + id + ".log"));
    pids_.push_back(stations.back());
  }
  for (pid_t p : stations) {
    const auto status = WaitExit(p, 60s);
    ASSERT_TRUE(status.has_value());
    EXPECT_EQ(*status, 0);
  }
  std::this_thread::sleep_for(500ms);
  kill(console, SIGINT);
  const auto console_status = WaitExit(console, 20s);
  ASSERT_TRUE(console_status.has_value());
  ASSERT_EQ(*console_status, 0) << ReadFile(dir_ + "/instructor.log");

  // Every station re-simulates with every step's hash matching.
  const std::string log = dir_ + "/resim.log";
  ASSERT_EQ(RunReplay({file, "--resimulate"}, log), 0) << ReadFile(log);
  const std::string out = ReadFile(log);
  for (const char* id : kTrainingScenes) ExpectEveryStepHashMatched(out, id);
  // The cues were applied (and re-applied at their steps): every station acknowledged them
  // (the tremor cue switched off again among them).
  record::SessionReader reader(file);
  std::size_t events = 0;
  reader.ForEach({static_cast<int>(record::TopicIndex::kTaskEvent)},
                 [&](const record::MessageView&) { return ++events, true; });
  EXPECT_GE(events, 3 * std::size(kTrainingScenes));
  EXPECT_TRUE(reader.problems().empty());

  // One device sample moved by 1 nm: reported at that station and step.
  const std::string altered = dir_ + "/altered.db";
  {
    std::ifstream src(file, std::ios::binary);
    std::ofstream dst(altered, std::ios::binary);
    dst << src.rdbuf();
  }
  ASSERT_TRUE(AlterDeviceInput(altered, "grasp", 1234));
  const std::string log2 = dir_ + "/resim-altered.log";
  EXPECT_EQ(RunReplay({altered, "--resimulate"}, log2), 1) << ReadFile(log2);
  const std::string out2 = ReadFile(log2);
  EXPECT_NE(out2.find("station grasp diverges at step 1234"), std::string::npos) << out2;
  // The other stations still match.
  EXPECT_NE(out2.find("station tremor_hold (session"), std::string::npos) << out2;
  EXPECT_EQ(out2.find("DIVERGES", out2.find("station knot_placement")), std::string::npos);

  // The CSV export: one row per recorded DeviceInput (and a header).
  std::size_t inputs = 0;
  reader.ForEach({static_cast<int>(record::TopicIndex::kDeviceInput)},
                 [&](const record::MessageView&) { return ++inputs, true; });
  ASSERT_EQ(RunReplay({file, "--export-csv", dir_ + "/csv", "--summary", dir_ + "/summary.md"},
                      dir_ + "/export.log"),
            0)
      << ReadFile(dir_ + "/export.log");
  std::ifstream csv(dir_ + "/csv/device_input.csv");
  std::size_t lines = 0;
  for (std::string l; std::getline(csv, l);) ++lines;
  EXPECT_EQ(lines, inputs + 1);
  const std::string summary = ReadFile(dir_ + "/summary.md");
  for (const char* id : kTrainingScenes) EXPECT_NE(summary.find(id), std::string::npos);

  // Replayed over DDS at the live rate (faster replays wait on the console's reliable
  // readers on a loaded machine), the session is mirrored by an instructor as if live.
  instructor::InstructorOptions options;
  options.dds.profile_file = net::DefaultDdsProfileFile();
  options.dds.domain_id = kReplayDomain;
  options.receive_inputs = true;  // the replayed inputs are counted below
  instructor::Instructor mirror(options);
  const std::string log3 = dir_ + "/replay.log";
  ASSERT_EQ(RunReplay({file, "--speed", "1", "--from", "1", "--to", "2.5", "--domain",
                       std::to_string(kReplayDomain)},
                      log3),
            0)
      << ReadFile(log3);
  const auto stations_seen = mirror.Stations();
  std::size_t mirrored = 0;
  std::string seen;
  for (const auto& v : stations_seen) {
    if (v.tool.count > 0 && v.inputs_received > 0 && !v.info.scene.empty()) ++mirrored;
    seen += v.info.header.station_id + ": scene '" + v.info.scene + "', " +
            std::to_string(v.tool.count) + " tool states, " + std::to_string(v.inputs_received) +
            " inputs\n";
  }
  EXPECT_EQ(mirrored, std::size(kTrainingScenes)) << seen << ReadFile(log3);
}

// The composite needle-through-tissue scene (FEM tissue, puncture) and the bimanual thread
// scene (two devices' inputs) record and re-simulate with every step's hash matching.
TEST_F(RecordReplayTest, TheTissueAndBimanualScenesReSimulate) {
  const std::string file = dir_ + "/heavy.db";
  const pid_t console =
      Spawn("microdex-instructor",
            {"--headless", "--table-period", "0", "--domain", std::to_string(kDomain), "--record",
             file, "--cue", "all:convergent:150@1.5"},
            dir_ + "/instructor-heavy.log");
  pids_.push_back(console);
  std::vector<pid_t> stations;
  for (std::size_t i = 0; i < std::size(kHeavyScenes); ++i) {
    const std::string id = kHeavyScenes[i];
    stations.push_back(
        Spawn("microdex-station",
              {"--scene", "assets/scenes/" + id + ".yaml", "--station-id", id, "--seed",
               std::to_string(60 + i), "--skill", "0.4", "--duration", "4", "--no-realtime",
               "--domain", std::to_string(kDomain), "--wait-for-recorder", "20"},
              dir_ + "/" + id + ".log"));
    pids_.push_back(stations.back());
  }
  for (std::size_t i = 0; i < stations.size(); ++i) {
    const auto status = WaitExit(stations[i], 60s);
    ASSERT_TRUE(status.has_value()) << kHeavyScenes[i];
    EXPECT_EQ(*status, 0) << ReadFile(dir_ + "/" + kHeavyScenes[i] + ".log");
  }
  std::this_thread::sleep_for(500ms);
  kill(console, SIGINT);
  const auto console_status = WaitExit(console, 20s);
  ASSERT_TRUE(console_status.has_value());
  ASSERT_EQ(*console_status, 0) << ReadFile(dir_ + "/instructor-heavy.log");

  const std::string log = dir_ + "/resim-heavy.log";
  ASSERT_EQ(RunReplay({file, "--resimulate"}, log), 0) << ReadFile(log);
  const std::string out = ReadFile(log);
  for (const char* id : kHeavyScenes) ExpectEveryStepHashMatched(out, id);
}

TEST_F(RecordReplayTest, AKilledRecorderLeavesAReadableFileUpToTheLast200Ms) {
  const std::string file = dir_ + "/killed.db";
  const pid_t station =
      Spawn("microdex-station",
            {"--scene", "assets/scenes/needle_tube.yaml", "--station-id", "k1", "--duration", "30",
             "--no-realtime", "--domain", std::to_string(kDomain), "--wait-for-recorder", "20"},
            dir_ + "/k1.log");
  pids_.push_back(station);
  const pid_t console = Spawn(
      "microdex-instructor",
      {"--headless", "--table-period", "0", "--domain", std::to_string(kDomain), "--record", file},
      dir_ + "/instructor.log");
  pids_.push_back(console);
  std::this_thread::sleep_for(3s);
  ASSERT_EQ(kill(console, 0), 0) << ReadFile(dir_ + "/instructor.log");
  kill(console, SIGKILL);
  const std::int64_t killed_ns = RealtimeNowNs();
  ASSERT_TRUE(WaitExit(console, 5s).has_value());
  kill(station, SIGTERM);
  WaitExit(station, 5s);

  record::SessionReader reader(file);  // throws if it does not open
  std::int64_t last_ns = 0;
  std::uint64_t next_step = 0, gaps = 0, inputs = 0;
  reader.ForEach({static_cast<int>(record::TopicIndex::kDeviceInput), "k1"},
                 [&](const record::MessageView& m) {
                   last_ns = std::max(last_ns, m.receive_ns);
                   if (m.step != next_step) ++gaps;
                   next_step = m.step + 1;
                   ++inputs;
                   return true;
                 });
  EXPECT_TRUE(reader.problems().empty()) << reader.problems().front();
  EXPECT_GT(inputs, 1000u);
  EXPECT_EQ(gaps, 0u);
  EXPECT_GE(last_ns, killed_ns - 200'000'000)
      << "the last " << (killed_ns - last_ns) * 1e-6 << " ms before the kill are missing";
}

// microdex-replay on bad files: exit 2 and one line on stderr naming the file and the fault.
TEST_F(RecordReplayTest, ReplayRefusesBadFilesWithOneLineNamingThem) {
  const std::string text = dir_ + "/notes.db";
  std::ofstream(text) << "not a recording, only text long enough for SQLite to read a header\n";
  const std::string missing = dir_ + "/missing.db";
  const struct {
    std::vector<std::string> args;
    std::string expected;
  } cases[] = {
      {{text, "--resimulate"}, text + ": not an SQLite database"},
      {{text, "--export-csv", dir_ + "/csv"}, text + ": not an SQLite database"},
      {{missing}, missing + ": no such file"},
      {{missing, "--speed", "0"}, "--speed"},
  };
  for (const auto& c : cases) {
    const std::string log = dir_ + "/bad.log";
    EXPECT_EQ(RunReplay(c.args, log), 2) << c.expected;
    const std::string out = ReadFile(log);
    EXPECT_EQ(out, "microdex-replay: " + out.substr(17)) << out;
    EXPECT_NE(out.find(c.expected), std::string::npos) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  }
}

}  // namespace
}  // namespace microdex
