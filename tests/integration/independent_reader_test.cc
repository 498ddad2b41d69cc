// A DDS participant written here from the generated IDL types only (not the apps' net layer)
// reads a station's topics and checks their contents; it also sends the station a cue and a
// malformed cue, which come back as TaskEvents. A station whose scene has no needle module
// publishes no NeedleState.
#include <gtest/gtest.h>

#include <cmath>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <map>

#include "cue_commandPubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "needle_statePubSubTypes.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"
#include "tests/integration/process.h"
#include "tool_statePubSubTypes.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

constexpr int kDomain = 82;

// Plain Fast DDS: the participant from the default profile of the loopback XML file given
// by FASTRTPS_DEFAULT_PROFILES_FILE, endpoints from the XML profile names of the topic
// table in common/net/README.md.
class RawParticipant {
 public:
  RawParticipant() {
    auto* f = dds::DomainParticipantFactory::get_instance();
    f->load_profiles();
    participant_ = f->create_participant_with_profile(kDomain, "microdex_participant");
    if (participant_ == nullptr) throw std::runtime_error("participant");
    sub_ = participant_->create_subscriber(participant_->get_default_subscriber_qos());
    pub_ = participant_->create_publisher(participant_->get_default_publisher_qos());
  }
  ~RawParticipant() {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  template <class PubSub>
  dds::Topic* Topic(const char* name) {
    dds::TypeSupport t(new PubSub());
    t.register_type(participant_);
    auto* existing = participant_->find_topic(name, eprosima::fastrtps::Duration_t(0, 0));
    if (existing) return existing;
    return participant_->create_topic(name, t.get_type_name(),
                                      participant_->get_default_topic_qos());
  }
  template <class PubSub>
  dds::DataReader* Reader(const char* topic, const char* profile) {
    return sub_->create_datareader_with_profile(Topic<PubSub>(topic), profile);
  }
  template <class PubSub>
  dds::DataWriter* Writer(const char* topic, const char* profile) {
    return pub_->create_datawriter_with_profile(Topic<PubSub>(topic), profile);
  }

 private:
  dds::DomainParticipant* participant_ = nullptr;
  dds::Subscriber* sub_ = nullptr;
  dds::Publisher* pub_ = nullptr;
};

template <class Msg>
std::vector<Msg> TakeAll(dds::DataReader* r) {
  std::vector<Msg> out;
  Msg m;
  dds::SampleInfo info;
  while (r->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) out.push_back(m);
  }
  return out;
}

double Norm(const std::array<double, 4>& q) {
  return std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
}

TEST(IndependentReader, StationTopicsCarryWhatTheyShould) {
  const std::string dir = "/tmp/microdex-ir-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  RawParticipant p;
  auto* info_r =
      p.Reader<msg::StationInfoPubSubType>("microdex/station_info", "microdex_station_info_reader");
  auto* input_r =
      p.Reader<msg::DeviceInputPubSubType>("microdex/device_input", "microdex_device_input_reader");
  auto* needle_r =
      p.Reader<msg::NeedleStatePubSubType>("microdex/needle_state", "microdex_mirror_reader");
  auto* tool_r =
      p.Reader<msg::ToolStatePubSubType>("microdex/tool_state", "microdex_mirror_reader");
  auto* tele_r =
      p.Reader<msg::TelemetryPubSubType>("microdex/telemetry", "microdex_telemetry_reader");
  auto* event_r =
      p.Reader<msg::TaskEventPubSubType>("microdex/task_event", "microdex_events_reader");
  auto* cue_w = p.Writer<msg::CueCommandPubSubType>("microdex/cue_command", "microdex_cue_writer");
  ASSERT_TRUE(info_r && input_r && needle_r && tool_r && tele_r && event_r && cue_w);

  const std::string src = testing::SourceDir();
  std::vector<pid_t> pids;
  pids.push_back(
      testing::Spawn("microdex-station",
                     {"--scene", src + "/assets/scenes/needle_tube.yaml", "--station-id",
                      "raw-needle", "--domain", std::to_string(kDomain), "--skill", "0.5"},
                     dir + "/needle.log"));
  pids.push_back(
      testing::Spawn("microdex-station",
                     {"--scene", src + "/assets/scenes/needle_tremor_only.yaml", "--station-id",
                      "raw-tremor", "--domain", std::to_string(kDomain), "--skill", "0.0"},
                     dir + "/tremor.log"));

  std::map<std::string, msg::StationInfo> infos;
  std::map<std::string, std::vector<msg::DeviceInput>> inputs;
  std::map<std::string, std::vector<msg::NeedleState>> needles;
  std::map<std::string, std::vector<msg::ToolState>> tools;
  std::map<std::string, std::vector<msg::Telemetry>> telemetry;
  std::vector<msg::TaskEvent> events;
  auto poll = [&] {
    for (auto& m : TakeAll<msg::StationInfo>(info_r)) infos[m.station_id().c_str()] = m;
    for (auto& m : TakeAll<msg::DeviceInput>(input_r)) inputs[m.station_id().c_str()].push_back(m);
    for (auto& m : TakeAll<msg::NeedleState>(needle_r))
      needles[m.station_id().c_str()].push_back(m);
    for (auto& m : TakeAll<msg::ToolState>(tool_r)) tools[m.station_id().c_str()].push_back(m);
    for (auto& m : TakeAll<msg::Telemetry>(tele_r)) telemetry[m.station_id().c_str()].push_back(m);
    for (auto& m : TakeAll<msg::TaskEvent>(event_r)) events.push_back(m);
  };
  const bool enough = testing::WaitUntil(
      [&] {
        poll();
        return infos.size() == 2 && inputs["raw-needle"].size() >= 1500 &&
               needles["raw-needle"].size() >= 30 && tools["raw-tremor"].size() >= 30 &&
               telemetry["raw-needle"].size() >= 5;
      },
      20s);
  ASSERT_TRUE(enough) << "infos " << infos.size() << " inputs " << inputs["raw-needle"].size();

  // A cue from this participant, and a malformed one (unknown kind).
  msg::CueCommand cue;
  cue.station_id("raw-needle");
  cue.session_id("raw-test");
  cue.cue_id(777);
  cue.kind(msg::CUE_DIVERGENT_FIELD);
  cue.param(150);
  cue.issuer("raw");
  ASSERT_TRUE(cue_w->write(&cue));
  cue.cue_id(778);
  cue.kind(static_cast<msg::CueKind>(42));
  ASSERT_TRUE(cue_w->write(&cue));
  ASSERT_TRUE(testing::WaitUntil(
      [&] {
        poll();
        bool applied = false, rejected = false;
        for (const auto& e : events) {
          if (e.cue_id() == 777 && e.kind() == msg::EVENT_CUE_APPLIED) applied = true;
          if (e.cue_id() == 778 && e.kind() == msg::EVENT_CUE_REJECTED) rejected = true;
        }
        return applied && rejected;
      },
      5s));
  testing::KillAll(pids);

  // StationInfo: who, what scene, which modules.
  const auto& ni = infos["raw-needle"];
  EXPECT_NE(std::string(ni.scene().c_str()).find("needle_tube.yaml"), std::string::npos);
  ASSERT_EQ(ni.modules().size(), 2u);
  EXPECT_EQ(std::string(ni.modules()[0].name().c_str()), "needle");
  EXPECT_EQ(ni.haptic_rate_hz(), 1000.0);
  EXPECT_EQ(ni.skill(), 0.5);
  ASSERT_EQ(infos["raw-tremor"].modules().size(), 1u);

  // DeviceInput: every step once, in order, one session; poses near the tube's path circle.
  const auto& in = inputs["raw-needle"];
  for (std::size_t i = 1; i < in.size(); ++i) {
    EXPECT_EQ(in[i].step(), in[i - 1].step() + 1) << "step gap at " << i;
    EXPECT_GE(in[i].stamp_ns(), in[i - 1].stamp_ns());
    EXPECT_EQ(in[i].session_id(), in[0].session_id());
  }
  for (const auto& d : in) {
    EXPECT_NEAR(Norm(d.q_WT()), 1.0, 1e-9);
    const double rho = std::hypot(d.p_WT()[0], d.p_WT()[1]);
    EXPECT_NEAR(rho, 5e-3, 1.5e-3);  // needle tail near its 5 mm path circle
    EXPECT_LT(std::abs(d.p_WT()[2]), 1.5e-3);
  }

  // NeedleState: clearance within [−r, r] (r = 0.5 mm), contact flag consistent with it.
  for (const auto& n : needles["raw-needle"]) {
    ASSERT_EQ(n.status(), 0);
    EXPECT_LE(n.clearance_m(), 0.5e-3 + 1e-12);
    EXPECT_GT(n.clearance_m(), -0.5e-3);
    EXPECT_EQ(n.contact() == 1, n.clearance_m() <= 0);
    EXPECT_NEAR(Norm(n.q_WN()), 1.0, 1e-9);
  }
  // Mirrored at about 60 Hz: against the DeviceInput count (1 kHz) over the same time.
  EXPECT_EQ(needles["raw-tremor"].size(), 0u) << "a station without the needle module "
                                                 "published NeedleState";
  // Telemetry: 10 Hz windows of about 100 ticks, 1 ms mean period, both modules reported.
  for (const auto& t : telemetry["raw-needle"]) {
    EXPECT_GT(t.ticks(), 50u);
    EXPECT_NEAR(t.period_mean_s(), 1e-3, 0.2e-3);
    ASSERT_EQ(t.modules().size(), 2u);
    EXPECT_EQ(std::string(t.modules()[0].name().c_str()), "needle");
  }
  // ToolState of the tremor-only station reports the measured tremor (novice: tens of µm).
  const auto& last_tool = tools["raw-tremor"].back();
  EXPECT_GT(last_tool.tremor_rms_m(), 10e-6);
  EXPECT_LT(last_tool.tremor_rms_m(), 500e-6);
}

}  // namespace
}  // namespace microdex
