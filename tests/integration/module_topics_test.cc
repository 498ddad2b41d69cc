// A station builds only the modules its scene names and publishes only their topics: a
// participant written here from the generated IDL types only (not the apps' net layer) lists
// the writers each station's participant announces (needle-only, thread-only, tissue-only and
// thread + tissue scenes), and reads ThreadState and TissueState to check their contents
// against the scenes (anchor, link lengths against the reported strain, the tissue patch and
// its held edges).
#include <fastdds/rtps/common/InstanceHandle.h>
#include <fastdds/rtps/writer/WriterDiscoveryInfo.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "station_infoPubSubTypes.h"
#include "tests/integration/process.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

constexpr int kDomain = 84;

std::string PrefixKey(const rtps::GuidPrefix_t& p) {
  std::ostringstream os;
  os << p;
  return os.str();
}

// Remembers every remote writer's topic by its participant (GUID prefix).
class WriterLister : public dds::DomainParticipantListener {
 public:
  void on_publisher_discovery(dds::DomainParticipant*, rtps::WriterDiscoveryInfo&& info) override {
    if (info.status != rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) return;
    std::lock_guard<std::mutex> lock(mutex_);
    topics_[PrefixKey(info.info.guid().guidPrefix)].insert(info.info.topicName().to_string());
  }
  std::set<std::string> Topics(const std::string& prefix) {
    std::lock_guard<std::mutex> lock(mutex_);
    return topics_[prefix];
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::set<std::string>> topics_;
};

template <class PubSub>
dds::DataReader* Reader(dds::DomainParticipant* p, dds::Subscriber* sub, const char* topic,
                        const char* profile) {
  dds::TypeSupport t(new PubSub());
  t.register_type(p);
  dds::Topic* tp = p->create_topic(topic, t.get_type_name(), p->get_default_topic_qos());
  return sub->create_datareader_with_profile(tp, profile);
}

TEST(ModuleTopics, StationsPublishOnlyTheirModulesTopics) {
  const std::string dir = "/tmp/microdex-mt-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  auto* factory = dds::DomainParticipantFactory::get_instance();
  factory->load_profiles();
  WriterLister lister;
  dds::DomainParticipant* p =
      factory->create_participant_with_profile(kDomain, "microdex_participant", &lister);
  ASSERT_NE(p, nullptr);
  dds::Subscriber* sub = p->create_subscriber(p->get_default_subscriber_qos());
  auto* info_r = Reader<msg::StationInfoPubSubType>(p, sub, "microdex/station_info",
                                                    "microdex_station_info_reader");
  auto* thread_r =
      Reader<msg::ThreadStatePubSubType>(p, sub, "microdex/thread_state", "microdex_mirror_reader");
  auto* tissue_r =
      Reader<msg::TissueStatePubSubType>(p, sub, "microdex/tissue_state", "microdex_mirror_reader");
  ASSERT_TRUE(info_r && thread_r && tissue_r);

  const std::string scenes = testing::SourceDir() + "/assets/scenes/";
  const std::map<std::string, std::string> station_scene = {
      {"mt-needle", "needle_tube_minimal.yaml"},
      {"mt-thread", "thread_pull.yaml"},
      {"mt-tissue", "tissue_press.yaml"},
      {"mt-both", "suture_on_tissue.yaml"}};
  std::vector<pid_t> pids;
  for (const auto& [id, file] : station_scene) {
    pids.push_back(testing::Spawn("microdex-station",
                                  {"--scene", scenes + file, "--station-id", id, "--domain",
                                   std::to_string(kDomain), "--skill", "0.5"},
                                  dir + "/" + id + ".log"));
  }

  std::map<std::string, std::string> station_prefix;  // station id → participant prefix
  std::map<std::string, std::vector<msg::ThreadState>> threads;
  std::map<std::string, std::vector<msg::TissueState>> tissues;
  auto poll = [&] {
    msg::StationInfo info;
    dds::SampleInfo si;
    while (info_r->take_next_sample(&info, &si) == ReturnCode_t::RETCODE_OK) {
      if (!si.valid_data) continue;
      const rtps::GUID_t writer = rtps::iHandle2GUID(si.publication_handle);
      station_prefix[info.station_id().c_str()] = PrefixKey(writer.guidPrefix);
    }
    msg::ThreadState t;
    while (thread_r->take_next_sample(&t, &si) == ReturnCode_t::RETCODE_OK) {
      if (si.valid_data) threads[t.station_id().c_str()].push_back(t);
    }
    msg::TissueState s;
    while (tissue_r->take_next_sample(&s, &si) == ReturnCode_t::RETCODE_OK) {
      if (si.valid_data) tissues[s.station_id().c_str()].push_back(s);
    }
  };
  // Until every station is known and the tissue station has pressed at least 0.3 mm deep
  // (its first pass goes 1 mm deep after about 2 s), with the thread's knot recognised.
  const bool enough = testing::WaitUntil(
      [&] {
        poll();
        bool pressed = false;
        for (const auto& s : tissues["mt-tissue"]) pressed |= s.max_displacement_m() > 0.3e-3;
        const bool knot = !threads["mt-thread"].empty() &&
                          !std::string(threads["mt-thread"].back().knot().c_str()).empty();
        return station_prefix.size() == 4 && pressed && knot && threads["mt-both"].size() > 10;
      },
      25s);
  testing::KillAll(pids);
  ASSERT_TRUE(enough) << "stations " << station_prefix.size() << ", thread samples "
                      << threads["mt-thread"].size() << ", tissue samples "
                      << tissues["mt-tissue"].size();

  // Writers per station: the common topics, plus exactly the scene's module states.
  // (CueOverlay: every station, empty while no visual cue is on. SceneDescription: every
  // station whose scene came from a file, as all of these do.)
  const std::set<std::string> common = {"microdex/station_info", "microdex/device_input",
                                        "microdex/cue_overlay",  "microdex/tool_state",
                                        "microdex/telemetry",    "microdex/task_event",
                                        "microdex/score",        "microdex/scene_description"};
  const std::map<std::string, std::set<std::string>> modules = {
      {"mt-needle", {"microdex/needle_state"}},
      {"mt-thread", {"microdex/thread_state"}},
      {"mt-tissue", {"microdex/tissue_state"}},
      {"mt-both", {"microdex/thread_state", "microdex/tissue_state"}}};
  for (const auto& [id, extra] : modules) {
    std::set<std::string> expected = common;
    expected.insert(extra.begin(), extra.end());
    EXPECT_EQ(lister.Topics(station_prefix[id]), expected) << id;
  }
  EXPECT_TRUE(threads["mt-needle"].empty() && tissues["mt-needle"].empty());
  EXPECT_TRUE(tissues["mt-thread"].empty()) << "the thread-only station published TissueState";
  EXPECT_TRUE(threads["mt-tissue"].empty()) << "the tissue-only station published ThreadState";

  // ThreadState (thread_pull.yaml): 65 nodes of the 30 mm nylon, node 0 at the anchor, the
  // grasped last node near the tool's path, link lengths agreeing with the reported strain.
  const double rest_m = 0.03 / 64;
  for (const auto& t : threads["mt-thread"]) {
    ASSERT_EQ(t.nodes().size(), 65u);
    EXPECT_EQ(t.grasped_node(), 64);
    EXPECT_LT(std::hypot(t.nodes()[0].x(), t.nodes()[0].y(), t.nodes()[0].z()), 1e-12);
    const auto& end = t.nodes()[64];
    EXPECT_NEAR(end.x(), 0.03, 3e-3);
    EXPECT_LT(std::abs(end.y()), 3e-3);
    double max_strain = 0;
    for (std::size_t i = 0; i + 1 < t.nodes().size(); ++i) {
      const auto& a = t.nodes()[i];
      const auto& b = t.nodes()[i + 1];
      const double l = std::hypot(b.x() - a.x(), b.y() - a.y(), b.z() - a.z());
      max_strain = std::max(max_strain, std::abs(l - rest_m) / rest_m);
    }
    EXPECT_NEAR(t.max_strain(), max_strain, 1e-9);
    const double f = std::hypot(t.f_T_W()[0], t.f_T_W()[1], t.f_T_W()[2]);
    EXPECT_LE(f, 2.0);
  }
  EXPECT_EQ(std::string(threads["mt-thread"].back().knot().c_str()), "none");

  // TissueState (tissue_press.yaml): the 2 cm patch at (−1, −1) cm, a 65 × 65 display grid,
  // the edges held, nothing above the surface nor deeper than the tool (1 mm + the trainee's
  // drift), and the reported depth the deepest value.
  for (const auto& s : tissues["mt-tissue"]) {
    ASSERT_EQ(s.nodes_x(), 65u);
    ASSERT_EQ(s.nodes_y(), 65u);
    ASSERT_EQ(s.displacement_m().size(), 65u * 65u);
    EXPECT_EQ(s.length_x_m(), 0.02);
    EXPECT_EQ(s.p_WS()[0], -0.01);
    EXPECT_LE(s.status(), 1);
    float deepest = 0;
    for (std::uint32_t j = 0; j < 65; ++j) {
      for (std::uint32_t i = 0; i < 65; ++i) {
        const float w = s.displacement_m()[j * 65 + i];
        EXPECT_LE(w, 1e-12f);
        EXPECT_GE(w, -2.5e-3f);
        if (i == 0 || j == 0 || i == 64 || j == 64) {
          EXPECT_NEAR(w, 0.0f, 1e-12f);
        }
        deepest = std::min(deepest, w);
      }
    }
    // The display grid samples the field, so it is at most as deep as the contact nodes.
    EXPECT_LE(-deepest, s.max_displacement_m() * (1 + 1e-5) + 1e-9);
  }
  sub->delete_contained_entities();
  p->delete_contained_entities();
  factory->delete_participant(p);
}

}  // namespace
}  // namespace microdex
