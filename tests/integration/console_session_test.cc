// The console's session controls (instructor/console_session.h) with a live station over DDS on
// loopback: a recording started while the station runs begins with its StationInfo and then
// holds its states; a second start and a replay of a live station are refused with the reason;
// once the station has left, the recording replays into the same console (the station alive
// again, with new states), paused and resumed, to its end, after which the station has left
// again. A seek back goes on from the earlier time without the station being lost and without
// its inputs refused as repeats. A second station's recording plays alongside the first on one
// transport (one pause holds both, one stop ends both). A recording is renamed (not while it is
// recorded, nor onto another) and deleted, except while it plays. A console not
// started ready to record refuses to start one.
#include "instructor/console_session.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <map>
#include <stdexcept>
#include <thread>

#include "common/record/recorded_topics.h"
#include "common/record/session_reader.h"
#include "instructor/instructor.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
using testing::WaitUntil;

constexpr int kDomain = 88;
const char* const kStation = "sess-a";

std::string Refusal(instructor::SessionControl& s, const std::string& message) {
  try {
    s.Handle(instructor::ParseSessionMessage(message));
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

instructor::StationView Station(instructor::Instructor& console, const char* id = kStation) {
  return console.Station(id).value_or(instructor::StationView{});
}

TEST(ConsoleSession, RecordsALiveStationFromTheMiddleAndReplaysItIntoTheConsole) {
  std::string dir = "/tmp/microdex-it-console-session-XXXXXX";
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain;
  instructor::InstructorOptions options;
  options.dds = dds;
  options.recording_ready = true;
  instructor::Instructor console(options);
  instructor::SessionControl session(console, dir + "/recordings", dds);

  std::vector<pid_t> pids{testing::Spawn(
      "microdex-station",
      {"--scene", testing::SourceDir() + "/assets/scenes/needle_tube.yaml", "--station-id",
       kStation, "--duration", "5", "--domain", std::to_string(kDomain), "--no-realtime"},
      dir + "/station.log")};
  ASSERT_TRUE(WaitUntil([&] { return Station(console).tool.count > 30; }, 20s))
      << testing::ReadFile(dir + "/station.log");

  // From the middle of the station's run.
  const std::string started = session.Handle(instructor::ParseSessionMessage("record start first"));
  EXPECT_NE(started.find("\"file\":\"first.db\""), std::string::npos) << started;
  EXPECT_NE(Refusal(session, "record start second").find("already recording to first.db"),
            std::string::npos);
  EXPECT_NE(Refusal(session, "replay play first.db").find("is recording"), std::string::npos);
  EXPECT_NE(session.StatusJson().find("\"recording\":{\"file\":\"first.db\""), std::string::npos);
  std::this_thread::sleep_for(1500ms);
  const std::string stopped = session.Handle(instructor::ParseSessionMessage("record stop"));
  EXPECT_NE(stopped.find("\"dropped\":0"), std::string::npos) << stopped;
  EXPECT_NE(Refusal(session, "record stop").find("not recording"), std::string::npos);
  EXPECT_NE(Refusal(session, "record start first").find("exists already"), std::string::npos);

  {
    record::SessionReader reader(dir + "/recordings/first.db");
    EXPECT_TRUE(reader.problems().empty());
    std::map<int, int> count;
    int first_topic = -1;
    reader.ForEach({}, [&](const record::MessageView& m) {
      if (m.station == kStation && first_topic < 0) first_topic = m.topic;
      ++count[m.topic];
      return true;
    });
    EXPECT_EQ(first_topic, static_cast<int>(record::TopicIndex::kStationInfo))
        << "a recording begun later announces the station first";
    EXPECT_EQ(count[static_cast<int>(record::TopicIndex::kStationInfo)], 1);
    // 1.5 s of a 60 Hz mirror and the 1 kHz inputs, with slack for a loaded host.
    EXPECT_GT(count[static_cast<int>(record::TopicIndex::kToolState)], 40);
    EXPECT_GT(count[static_cast<int>(record::TopicIndex::kDeviceInput)], 500);
    const auto [first, last] = reader.TimeRange();
    EXPECT_GT(last - first, 1'000'000'000);
    EXPECT_EQ(reader.metadata().at("recorder_session"), console.session_id());
  }
  const auto listed = session.Recordings();
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].name, "first.db");
  EXPECT_EQ(listed[0].stations, std::vector<std::string>{kStation});
  EXPECT_GT(listed[0].seconds, 1.0);

  // The station is live: its replay would mix with it.
  EXPECT_NE(Refusal(session, "replay play first.db").find("station sess-a of first.db is live"),
            std::string::npos);
  EXPECT_NE(Refusal(session, "replay play none.db").find("no recording none.db"),
            std::string::npos);
  const auto status = testing::WaitExit(pids[0], 30s);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(*status, 0) << testing::ReadFile(dir + "/station.log");
  ASSERT_TRUE(
      WaitUntil([&] { return Station(console).presence == instructor::Presence::kDeparted; }, 10s));

  // A second station's run, recorded into a file of its own.
  const char* const kOther = "sess-b";
  pids.push_back(testing::Spawn(
      "microdex-station",
      {"--scene", testing::SourceDir() + "/assets/scenes/tremor_hold.yaml", "--station-id", kOther,
       "--duration", "3", "--domain", std::to_string(kDomain), "--no-realtime"},
      dir + "/station-b.log"));
  ASSERT_TRUE(WaitUntil([&] { return Station(console, kOther).tool.count > 10; }, 20s))
      << testing::ReadFile(dir + "/station-b.log");
  session.Handle(instructor::ParseSessionMessage("record start second"));
  std::this_thread::sleep_for(1200ms);
  session.Handle(instructor::ParseSessionMessage("record stop"));
  const auto status_b = testing::WaitExit(pids[1], 30s);
  ASSERT_TRUE(status_b.has_value());
  ASSERT_TRUE(WaitUntil(
      [&] { return Station(console, kOther).presence == instructor::Presence::kDeparted; }, 10s));
  const std::uint64_t tools_before = Station(console).tool.count;
  const int comebacks_before = Station(console).comebacks;
  const std::uint64_t inputs_before = Station(console).inputs_received;

  session.Handle(instructor::ParseSessionMessage("replay play first.db 1"));
  EXPECT_TRUE(session.replaying());
  EXPECT_NE(Refusal(session, "record start during").find("a replay is playing"), std::string::npos);
  ASSERT_TRUE(WaitUntil(
      [&] {
        const auto v = Station(console);
        return v.presence == instructor::Presence::kAlive && v.comebacks > comebacks_before &&
               v.tool.count > tools_before + 10;
      },
      15s))
      << session.StatusJson();
  session.Handle(instructor::ParseSessionMessage("replay pause"));
  EXPECT_NE(session.StatusJson().find("\"paused\":true"), std::string::npos);
  std::this_thread::sleep_for(300ms);  // what was in flight arrives
  const std::uint64_t paused_at = Station(console).tool.count;
  std::this_thread::sleep_for(500ms);
  EXPECT_EQ(Station(console).tool.count, paused_at) << "nothing is replayed while paused";
  session.Handle(instructor::ParseSessionMessage("replay pause"));

  // Seek back to near the start: the station is announced again by a new writer, so that its
  // inputs, whose steps the console has taken already, count as a new run's.
  ASSERT_TRUE(
      WaitUntil([&] { return Station(console).inputs_received > inputs_before + 600; }, 10s));
  EXPECT_NE(Refusal(session, "replay seek 99").find("past the end"), std::string::npos);
  EXPECT_NE(Refusal(session, "record delete first.db").find("is playing"), std::string::npos);
  const auto sought_from = Station(console);
  const std::uint64_t rejected_before = console.Rejected().total;
  session.Handle(instructor::ParseSessionMessage("replay seek 0.1"));
  EXPECT_NE(session.StatusJson().find("\"seeks\":1"), std::string::npos);
  ASSERT_TRUE(WaitUntil(
      [&] { return Station(console).inputs_received > sought_from.inputs_received + 300; }, 10s))
      << session.StatusJson();
  const auto sought = Station(console);
  EXPECT_EQ(sought.presence, instructor::Presence::kAlive);
  EXPECT_EQ(sought.comebacks, sought_from.comebacks) << "the station was not lost on the seek";
  EXPECT_EQ(console.Rejected().total, rejected_before) << console.Rejected().last_reason;
  EXPECT_LT(sought.last_input_step, sought_from.last_input_step)
      << "the inputs go on from the earlier time";
  session.Handle(instructor::ParseSessionMessage("replay speed 4"));
  ASSERT_TRUE(WaitUntil([&] { return !session.replaying(); }, 20s)) << session.StatusJson();
  const std::string done = session.StatusJson();
  EXPECT_NE(done.find("\"done\":true"), std::string::npos) << done;
  EXPECT_NE(done.find("\"stopped\":false"), std::string::npos) << done;
  EXPECT_NE(done.find("\"error\":\"\""), std::string::npos) << done;
  EXPECT_GT(Station(console).tool.count, paused_at);
  EXPECT_NE(done.find("\"seeks\":1"), std::string::npos) << done;
  EXPECT_TRUE(
      WaitUntil([&] { return Station(console).presence == instructor::Presence::kDeparted; }, 10s))
      << "the replayed station leaves at the end";

  // Two files played together, on one transport: the second joins at the first's position.
  EXPECT_NE(Refusal(session, "replay add second.db").find("nothing is playing"), std::string::npos);
  session.Handle(instructor::ParseSessionMessage("replay play first.db 1"));
  EXPECT_NE(Refusal(session, "replay add first.db").find("in this replay already"),
            std::string::npos);
  EXPECT_NE(Refusal(session, "replay play second.db").find("add to it"), std::string::npos);
  const std::string added = session.Handle(instructor::ParseSessionMessage("replay add second.db"));
  EXPECT_NE(added.find("\"type\":\"replay_added\""), std::string::npos) << added;
  ASSERT_TRUE(WaitUntil(
      [&] {
        return Station(console).presence == instructor::Presence::kAlive &&
               Station(console, kOther).presence == instructor::Presence::kAlive;
      },
      10s))
      << session.StatusJson();
  EXPECT_NE(session.StatusJson().find("\"files\":[\"first.db\",\"second.db\"]"), std::string::npos)
      << session.StatusJson();
  session.Handle(instructor::ParseSessionMessage("replay pause"));
  std::this_thread::sleep_for(300ms);
  const std::uint64_t a_paused = Station(console).tool.count;
  const std::uint64_t b_paused = Station(console, kOther).tool.count;
  std::this_thread::sleep_for(400ms);
  EXPECT_EQ(Station(console).tool.count, a_paused) << "one pause holds both";
  EXPECT_EQ(Station(console, kOther).tool.count, b_paused);
  session.Handle(instructor::ParseSessionMessage("replay pause"));
  ASSERT_TRUE(WaitUntil([&] { return Station(console, kOther).tool.count > b_paused + 5; }, 5s));
  session.Handle(instructor::ParseSessionMessage("replay stop"));
  EXPECT_FALSE(session.replaying());
  EXPECT_TRUE(WaitUntil(
      [&] {
        return Station(console).presence == instructor::Presence::kDeparted &&
               Station(console, kOther).presence == instructor::Presence::kDeparted;
      },
      10s))
      << "one stop ends both";

  // Deleted once it is not playing.
  EXPECT_NE(Refusal(session, "record delete none.db").find("no recording none.db"),
            std::string::npos);
  const std::string deleted =
      session.Handle(instructor::ParseSessionMessage("record delete first.db"));
  EXPECT_NE(deleted.find("\"type\":\"recording_deleted\""), std::string::npos) << deleted;
  struct stat st {};
  EXPECT_NE(stat((dir + "/recordings/first.db").c_str(), &st), 0);
  ASSERT_EQ(session.Recordings().size(), 1u);
  EXPECT_EQ(session.Recordings()[0].name, "second.db");
  // Renamed, and listed under its new name with its stations.
  EXPECT_NE(Refusal(session, "record rename none.db x").find("no recording none.db"),
            std::string::npos);
  const std::string renamed =
      session.Handle(instructor::ParseSessionMessage("record rename second.db lesson-b"));
  EXPECT_NE(renamed.find("\"name\":\"lesson-b.db\""), std::string::npos) << renamed;
  ASSERT_EQ(session.Recordings().size(), 1u);
  EXPECT_EQ(session.Recordings()[0].name, "lesson-b.db");
  EXPECT_EQ(session.Recordings()[0].stations, std::vector<std::string>{kOther});
  session.Handle(instructor::ParseSessionMessage("record start third"));
  EXPECT_NE(Refusal(session, "record rename third.db fourth").find("is being recorded"),
            std::string::npos);
  EXPECT_NE(Refusal(session, "record rename lesson-b.db third").find("third.db exists already"),
            std::string::npos);
  session.Handle(instructor::ParseSessionMessage("record stop"));
  EXPECT_EQ(session.StatusJson().find("first.db\",\"bytes"), std::string::npos);
  testing::KillAll(pids);
}

TEST(ConsoleSession, AConsoleNotReadyToRecordRefusesToStartOne) {
  instructor::InstructorOptions options;
  options.dds.profile_file = net::DefaultDdsProfileFile();
  options.dds.domain_id = kDomain;
  instructor::Instructor console(options);
  EXPECT_FALSE(console.recording_ready());
  try {
    console.StartRecording("/tmp/never-made.db");
    ADD_FAILURE() << "started";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("not started ready to record"), std::string::npos);
  }
  EXPECT_FALSE(console.StopRecording().has_value());
  EXPECT_EQ(console.RecordingPath(), "");
}

}  // namespace
}  // namespace microdex
