// The instructor's engine in one process, on the loopback profile: a station-side participant
// (the apps' net layer) announces a StationInfo and module states; the instructor lists it
// alive with its mirrors, sees its disposal as a departure, and a deleted participant as lost
// by the liveliness path (not by silence). Also the --cue argument and the text table.
#include "instructor/instructor.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "common/net/convert.h"
#include "instructor/cue_spec.h"
#include "station_infoPubSubTypes.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"

namespace microdex::instructor {
namespace {

using namespace std::chrono_literals;
constexpr int kDomain = 85;

bool WaitFor(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return done();
}

net::DdsOptions Options(const std::string& name) {
  net::DdsOptions o;
  o.profile_file = net::DefaultDdsProfileFile();
  o.domain_id = kDomain;
  o.participant_name = name;
  return o;
}

net::StationInfo Info(const std::string& id) {
  net::StationInfo info;
  info.header = {id, id + "-session", 0, 1};
  info.trainee = "t";
  info.scene = "assets/scenes/suture_on_tissue.yaml";
  info.modules = {"thread", "tissue"};
  info.build = "test";
  info.haptic_rate_hz = 1000;
  info.mirror_rate_hz = 60;
  info.skill = 0.5;
  info.device = "sim";
  return info;
}

TEST(Instructor, PresenceMirrorsDepartureAndLivelinessLoss) {
  InstructorOptions o;
  o.dds = Options("test-console");
  Instructor console(o);

  // Station A: info, a thread and a tissue state; then it leaves cleanly (dispose).
  auto a = std::make_unique<net::DdsContext>(Options("station-a"));
  auto* a_info = a->CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  auto* a_thread = a->CreateWriter<msg::ThreadStatePubSubType>(net::kThreadStateTopic);
  auto* a_tissue = a->CreateWriter<msg::TissueStatePubSubType>(net::kTissueStateTopic);
  msg::StationInfo info_msg;
  net::ToMsg(Info("st-a"), info_msg);
  ASSERT_TRUE(a_info->write(&info_msg));
  ASSERT_TRUE(WaitFor([&] { return console.Station("st-a").has_value(); }, 10s));
  net::ThreadState thread;
  thread.header = {"st-a", "st-a-session", 16, 2};
  thread.nodes = {{0, 0, 0}, {1e-3, 0, 0}};
  thread.knot = "none";
  thread.max_strain = 0.012;
  thread.grasped_node = 1;
  thread.f_T_W = {-0.03, 0, 0};
  net::TissueState tissue;
  tissue.header = {"st-a", "st-a-session", 16, 2};
  tissue.length_x_m = tissue.length_y_m = 0.02;
  tissue.nodes_x = tissue.nodes_y = 2;
  tissue.max_displacement_m = 0.8e-3;
  tissue.displacement_m = {0, 0, 0, -0.8e-3f};
  msg::ThreadState thread_msg;
  msg::TissueState tissue_msg;
  net::ToMsg(thread, thread_msg);
  net::ToMsg(tissue, tissue_msg);
  // Best-effort mirrors: write until the instructor has both.
  ASSERT_TRUE(WaitFor(
      [&] {
        a_thread->write(&thread_msg);
        a_tissue->write(&tissue_msg);
        const auto v = console.Station("st-a");
        return v->thread.latest.has_value() && v->tissue.latest.has_value();
      },
      10s));
  auto v = console.Station("st-a");
  EXPECT_EQ(v->presence, Presence::kAlive);
  EXPECT_EQ(v->info.modules, (std::vector<std::string>{"thread", "tissue"}));
  EXPECT_EQ(v->thread.latest->nodes.size(), 2u);
  EXPECT_EQ(v->thread.latest->knot, "none");
  EXPECT_EQ(v->tissue.latest->displacement_m.back(), -0.8e-3f);
  const std::string table = FormatStationTable(console.Stations(), MonotonicNowNs());
  EXPECT_NE(table.find("str 1.2% 0.03N"), std::string::npos) << table;
  EXPECT_NE(table.find("w 0.80mm"), std::string::npos) << table;
  EXPECT_NE(table.find("thread,tissue"), std::string::npos) << table;

  eprosima::fastrtps::rtps::InstanceHandle_t handle = a_info->register_instance(&info_msg);
  ASSERT_EQ(a_info->dispose(&info_msg, handle), ReturnCode_t::RETCODE_OK);
  ASSERT_TRUE(
      WaitFor([&] { return console.Station("st-a")->presence == Presence::kDeparted; }, 5s));
  EXPECT_EQ(console.Station("st-a")->lost_by, LossSignal::kNone);

  // Station B: alive, then its participant is deleted without disposing its StationInfo (a
  // station that vanishes rather than leaves; the SIGKILL case, where only the 1 s participant
  // lease tells, is station_instructor_test's). The liveliness path reports it.
  auto b = std::make_unique<net::DdsContext>(Options("station-b"));
  auto* b_info = b->CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  net::ToMsg(Info("st-b"), info_msg);
  ASSERT_TRUE(b_info->write(&info_msg));
  ASSERT_TRUE(WaitFor(
      [&] {
        const auto s = console.Station("st-b");
        return s && s->presence == Presence::kAlive;
      },
      10s));
  const auto t0 = std::chrono::steady_clock::now();
  b.reset();
  ASSERT_TRUE(WaitFor([&] { return console.Station("st-b")->presence == Presence::kLost; }, 3s));
  const double after_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const LossSignal by = console.Station("st-b")->lost_by;
  EXPECT_TRUE(by == LossSignal::kLiveliness || by == LossSignal::kNoWriters) << LossSignalName(by);
  EXPECT_LT(after_s, Instructor::kSilenceLimit_ns * 1e-9);
}

TEST(CueSpec, ParsesAndRejectsNamingTheArgument) {
  const CueSpec c = ParseCueSpec("st-2:convergent:300@12.5");
  EXPECT_EQ(c.station, "st-2");
  EXPECT_EQ(c.kind, cues::CueKind::kConvergentField);
  EXPECT_EQ(c.param, 300);
  EXPECT_EQ(c.at_s, 12.5);
  EXPECT_EQ(ParseCueSpec("all:clear:0").at_s, 0);
  // Every kind by name, and off.
  for (std::uint32_t k = 0; k < cues::kCueKindCount; ++k) {
    const auto kind = static_cast<cues::CueKind>(k);
    const std::string name = cues::CueKindName(kind);
    const double param = cues::CueParamLimits(kind).max;
    const CueSpec on = ParseCueSpec("all:" + name + ":" + std::to_string(param));
    EXPECT_EQ(on.kind, kind) << name;
    EXPECT_FALSE(on.off);
    const CueSpec off = ParseCueSpec("st-1:" + name + ":off@2");
    EXPECT_EQ(off.kind, kind) << name;
    EXPECT_TRUE(off.off);
    EXPECT_EQ(off.at_s, 2);
  }
  for (const char* bad : {"st-2:convergent", "st-2:vortex:3", "st-2:tremor:x", ":clear:0",
                          "st-2:clear:0@-1", "st-2:convergent:nan", "st-2:divergent:inf",
                          "st-2:convergent:2e6", "st-2:audio_click:2", "st-2:predictive:-1"}) {
    try {
      ParseCueSpec(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace microdex::instructor
