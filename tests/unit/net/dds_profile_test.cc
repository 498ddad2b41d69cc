// The loopback profile keeps every packet on the host, the endpoint profiles carry the QoS of
// the topic table (common/net/README.md), and stations of different courses (partition) or domains
// do not see each other.
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <gtest/gtest.h>

#include <chrono>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fstream>
#include <set>
#include <thread>

#include "common/net/convert.h"
#include "common/net/dds_context.h"
#include "station_infoPubSubTypes.h"

namespace microdex::net {
namespace {

using eprosima::fastrtps::types::ReturnCode_t;
namespace rtps = eprosima::fastrtps::rtps;
namespace transport = eprosima::fastdds::rtps;

// Each DDS test gets its own domain so parallel ctest runs cannot cross-talk.
constexpr int kDomain = 61;

// The Fast DDS shared-memory ports (input channels) this process has mapped.
int SharedMemoryPortsMapped() {
  std::ifstream maps("/proc/self/maps");
  std::set<std::string> ports;
  for (std::string line; std::getline(maps, line);) {
    const auto at = line.find("/dev/shm/fastrtps_port");
    if (at != std::string::npos) ports.insert(line.substr(at));
  }
  return static_cast<int>(ports.size());
}

DdsOptions Options(int domain, const std::string& partition) {
  DdsOptions o;
  o.profile_file = DefaultDdsProfileFile();
  o.domain_id = domain;
  o.partition = partition;
  return o;
}

TEST(DdsProfile, OptionsAreValidated) {
  DdsOptions o = Options(0, "");
  EXPECT_EQ(o.Validate(), "");
  o.domain_id = 300;
  EXPECT_NE(o.Validate().find("domain"), std::string::npos);
  o.domain_id = 1;
  o.partition = "course*";
  EXPECT_NE(o.Validate().find("partition"), std::string::npos);
  o.partition = "";
  o.profile_file = "";
  EXPECT_NE(o.Validate().find("dds-profile"), std::string::npos);
}

TEST(DdsProfile, MissingFileIsNamed) {
  DdsOptions o = Options(kDomain, "");
  o.profile_file = "/nonexistent/profile.xml";
  try {
    DdsContext c(o);
    FAIL() << "no exception";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/profile.xml"), std::string::npos);
  }
}

TEST(DdsProfile, LoopbackParticipantStaysOnTheHost) {
  DdsContext context(Options(kDomain, ""));  // loads the profile file
  dds::DomainParticipantQos qos;
  ASSERT_EQ(dds::DomainParticipantFactory::get_instance()->get_participant_qos_from_profile(
                kParticipantProfile, qos),
            ReturnCode_t::RETCODE_OK);
  EXPECT_FALSE(qos.transport().use_builtin_transports);
  int udp = 0, shm = 0;
  for (const auto& t : qos.transport().user_transports) {
    if (auto* u = dynamic_cast<transport::UDPv4TransportDescriptor*>(t.get())) {
      ++udp;
      ASSERT_EQ(u->interfaceWhiteList.size(), 1u);
      EXPECT_EQ(u->interfaceWhiteList[0], "127.0.0.1");
    } else if (dynamic_cast<transport::SharedMemTransportDescriptor*>(t.get()) != nullptr) {
      ++shm;
    } else {
      ADD_FAILURE() << "unexpected transport";
    }
  }
  EXPECT_EQ(udp, 1);
  EXPECT_EQ(shm, 1);
  const auto& builtin = qos.wire_protocol().builtin;
  EXPECT_TRUE(builtin.avoid_builtin_multicast);
  EXPECT_TRUE(builtin.metatrafficMulticastLocatorList.empty());
  ASSERT_FALSE(builtin.metatrafficUnicastLocatorList.empty());
  for (const auto& l : builtin.metatrafficUnicastLocatorList) {
    EXPECT_EQ(rtps::IPLocator::toIPv4string(l), "127.0.0.1");
  }
  ASSERT_FALSE(builtin.initialPeersList.empty());
  for (const auto& l : builtin.initialPeersList) {
    EXPECT_EQ(rtps::IPLocator::toIPv4string(l), "127.0.0.1");
  }
  EXPECT_TRUE(qos.wire_protocol().default_multicast_locator_list.empty());

  // And the participant actually created uses those locators.
  const auto& attrs = context.participant()->get_qos().wire_protocol();
  for (const auto& l : attrs.builtin.metatrafficUnicastLocatorList) {
    if (l.kind == LOCATOR_KIND_UDPv4) {
      EXPECT_EQ(rtps::IPLocator::toIPv4string(l), "127.0.0.1");
    }
  }
}

// The device bridge's participant: the same transports, discovery on 127.0.0.1, but no
// explicit data locators, so that the participant announces shared memory (and UDPv4 on the
// whitelisted 127.0.0.1 only). A name the file does not define falls back to the default.
TEST(DdsProfile, BridgeParticipantAnnouncesSharedMemoryAndStaysOnTheHost) {
  const int ports_before = SharedMemoryPortsMapped();
  {
    DdsContext plain(Options(kDomain, ""));
    EXPECT_EQ(SharedMemoryPortsMapped(), ports_before);
  }
  DdsOptions o = Options(kDomain, "");
  o.participant_profile = kDeviceBridgeParticipantProfile;
  DdsContext context(o);
  EXPECT_EQ(context.participant_profile(), kDeviceBridgeParticipantProfile);
  dds::DomainParticipantQos qos;
  ASSERT_EQ(dds::DomainParticipantFactory::get_instance()->get_participant_qos_from_profile(
                kDeviceBridgeParticipantProfile, qos),
            ReturnCode_t::RETCODE_OK);
  EXPECT_FALSE(qos.transport().use_builtin_transports);
  EXPECT_TRUE(qos.wire_protocol().default_unicast_locator_list.empty());
  EXPECT_TRUE(qos.wire_protocol().default_multicast_locator_list.empty());
  EXPECT_TRUE(qos.wire_protocol().builtin.avoid_builtin_multicast);
  for (const auto& l : qos.wire_protocol().builtin.metatrafficUnicastLocatorList) {
    EXPECT_EQ(rtps::IPLocator::toIPv4string(l), "127.0.0.1");
  }
  // The created participant listens on a shared-memory port (its data locator), which the
  // default participant of this file does not (it announces UDPv4 only).
  EXPECT_GT(SharedMemoryPortsMapped(), ports_before);

  DdsOptions missing = Options(kDomain, "");
  missing.participant_profile = "no_such_participant_profile";
  DdsContext fallback(missing);
  EXPECT_EQ(fallback.participant_profile(), kParticipantProfile);
}

TEST(DdsProfile, EndpointProfilesFollowTheTopicTable) {
  DdsContext context(Options(kDomain, ""));
  dds::DataWriter* info = context.CreateWriter<msg::StationInfoPubSubType>(kStationInfoTopic);
  const dds::DataWriterQos& iq = info->get_qos();
  EXPECT_EQ(iq.reliability().kind, dds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(iq.durability().kind, dds::TRANSIENT_LOCAL_DURABILITY_QOS);
  EXPECT_EQ(iq.liveliness().kind, dds::AUTOMATIC_LIVELINESS_QOS);
  EXPECT_EQ(iq.liveliness().lease_duration.seconds, 1);
  EXPECT_EQ(iq.liveliness().lease_duration.nanosec, 0u);

  dds::DataWriter* input = context.CreateWriter<msg::StationInfoPubSubType>(kDeviceInputTopic);
  EXPECT_EQ(input->get_qos().reliability().kind, dds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(input->get_qos().history().kind, dds::KEEP_ALL_HISTORY_QOS);

  dds::DataWriter* mirror = context.CreateWriter<msg::StationInfoPubSubType>(kNeedleStateTopic);
  // Reliable keep-last 240 (4 s at 60 Hz): the recorder's reliable readers get every state;
  // the console's best-effort readers match it and keep only the latest.
  EXPECT_EQ(mirror->get_qos().reliability().kind, dds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(mirror->get_qos().history().kind, dds::KEEP_LAST_HISTORY_QOS);
  EXPECT_EQ(mirror->get_qos().history().depth, 240);

  dds::DataReader* cue = context.CreateReader<msg::StationInfoPubSubType>(kCueCommandTopic);
  EXPECT_EQ(cue->get_qos().reliability().kind, dds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(cue->get_qos().durability().kind, dds::TRANSIENT_LOCAL_DURABILITY_QOS);

  dds::DataReader* events = context.CreateReader<msg::StationInfoPubSubType>(kTaskEventTopic);
  EXPECT_EQ(events->get_qos().reliability().kind, dds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(events->get_qos().history().kind, dds::KEEP_ALL_HISTORY_QOS);
}

// Takes every valid sample; returns the station ids seen.
std::vector<std::string> TakeIds(dds::DataReader* reader) {
  std::vector<std::string> ids;
  msg::StationInfo m;
  dds::SampleInfo info;
  while (reader->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) ids.push_back(m.station_id().c_str());
  }
  return ids;
}

TEST(DdsProfile, CoursesAndDomainsAreIsolated) {
  DdsContext station_a(Options(kDomain + 1, "course-a"));
  DdsContext instructor_a(Options(kDomain + 1, "course-a"));
  DdsContext instructor_b(Options(kDomain + 1, "course-b"));
  DdsContext instructor_other_domain(Options(kDomain + 2, "course-a"));
  dds::DataReader* ra = instructor_a.CreateReader<msg::StationInfoPubSubType>(kStationInfoTopic);
  dds::DataReader* rb = instructor_b.CreateReader<msg::StationInfoPubSubType>(kStationInfoTopic);
  dds::DataReader* rd =
      instructor_other_domain.CreateReader<msg::StationInfoPubSubType>(kStationInfoTopic);
  dds::DataWriter* w = station_a.CreateWriter<msg::StationInfoPubSubType>(kStationInfoTopic);

  StationInfo info;
  info.header = {"station-a1", "s", 1, 0};
  msg::StationInfo m;
  ToMsg(info, m);
  ASSERT_TRUE(w->write(&m));

  std::vector<std::string> got_a;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (got_a.empty() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    got_a = TakeIds(ra);
  }
  ASSERT_EQ(got_a, std::vector<std::string>{"station-a1"});
  // Same course, same domain received it; give the others the same time again.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_TRUE(TakeIds(rb).empty()) << "another course saw the station";
  EXPECT_TRUE(TakeIds(rd).empty()) << "another domain saw the station";
  dds::PublicationMatchedStatus matched;
  w->get_publication_matched_status(matched);
  EXPECT_EQ(matched.current_count, 1);
}

}  // namespace
}  // namespace microdex::net
