#pragma once
// One DDS participant with its publisher and subscriber, created from the XML profile file
// (deploy/dds/*.xml): the participant from the named participant profile
// (create_participant_with_profile: a copied DomainParticipantQos would drop the XML
// transports), topics, writers and readers from their named profiles. QoS is never set here,
// with two exceptions, both deployment values given on the command line: the partition (the
// course), added to the publisher and subscriber QoS loaded from the XML; and DDS Security
// (`--security DIR`, dds_security.h): its plugin properties are added to the participant QoS
// read from the participant profile, and the partition becomes COURSE/STATION (COURSE/* for
// the instructor), the unit the permissions grant.
//
// Not thread-safe: the thread that owns the context creates, uses and destroys its entities.

#include <exception>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <string>
#include <vector>

#include "common/net/topics.h"

namespace microdex::net {

namespace dds = eprosima::fastdds::dds;

struct DdsOptions {
  std::string profile_file;  // XML profiles; must define kParticipantProfile
  int domain_id = 0;         // 0..232
  std::string partition;     // empty: the default partition
  std::string participant_name = "microdex";
  // The participant profile; empty, or a name the file does not define: kParticipantProfile.
  // (The DDS device bridge asks for kDeviceBridgeParticipantProfile.)
  std::string participant_profile;
  // DDS Security: the identity directory (deploy/security/make-course); empty: plain DDS.
  std::string security_dir;
  // With security: the station this participant acts for (a station, a device driver), or
  // empty for the instructor (every station).
  std::string security_station;
  // Called by Fast DDS from the participant's creation on (its discovery callbacks: the
  // instructor learns each remote writer's partition); nullptr: none. Not owned: it must
  // outlive the context.
  dds::DomainParticipantListener* participant_listener = nullptr;
  // Empty when valid; otherwise a one-line reason naming the field.
  std::string Validate() const;
};

// The profile file used when none is given: $FASTRTPS_DEFAULT_PROFILES_FILE if set, else
// deploy/dds/loopback.xml under the working directory, else under the source tree.
std::string DefaultDdsProfileFile();

// A generated type support whose deserialize never throws: Fast CDR throws on a malformed
// payload (e.g. "Unexpected CDR type received in Cdr::read_encapsulation" for a bad
// encapsulation header, found by tests/fuzz/sample_validator_fuzz.cc), and the generated code
// lets it out of DataReader::take_next_sample, which would end the receiving thread and the
// app on one hostile sample. Such a sample is refused (false) and Fast DDS drops it.
template <class PubSubType>
class CheckedPubSubType : public PubSubType {
 public:
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    try {
      return PubSubType::deserialize(payload, data);
    } catch (const std::exception&) {
      return false;
    }
  }
};

class DdsContext {
 public:
  // Throws std::runtime_error naming the file, profile or entity that failed.
  explicit DdsContext(const DdsOptions& options);
  ~DdsContext();
  DdsContext(const DdsContext&) = delete;
  DdsContext& operator=(const DdsContext&) = delete;

  // Registers PubSubType (once) and creates the topic from spec.topic_profile (once).
  template <class PubSubType>
  dds::Topic* GetTopic(const TopicSpec& spec) {
    return GetTopicImpl(spec, [] { return dds::TypeSupport(new CheckedPubSubType<PubSubType>()); });
  }
  // Writer/reader from the spec's XML profile; throws when the profile is missing.
  template <class PubSubType>
  dds::DataWriter* CreateWriter(const TopicSpec& spec) {
    return CreateWriterImpl(GetTopic<PubSubType>(spec), spec);
  }
  template <class PubSubType>
  dds::DataReader* CreateReader(const TopicSpec& spec) {
    return CreateReaderImpl(GetTopic<PubSubType>(spec), spec);
  }

  // Deletes a writer this context created (its readers see it go).
  void DeleteWriter(dds::DataWriter* writer);

  dds::DomainParticipant* participant() { return participant_; }
  const DdsOptions& options() const { return options_; }
  // The participant profile the participant was created from.
  const std::string& participant_profile() const { return participant_profile_; }
  // The partition of the publisher and subscriber (empty: the default partition).
  const std::string& partition() const { return partition_; }

 private:
  dds::Topic* GetTopicImpl(const TopicSpec& spec, dds::TypeSupport (*make_type)());
  dds::DataWriter* CreateWriterImpl(dds::Topic* topic, const TopicSpec& spec);
  dds::DataReader* CreateReaderImpl(dds::Topic* topic, const TopicSpec& spec);

  DdsOptions options_;
  std::string participant_profile_;
  std::string partition_;
  dds::DomainParticipant* participant_ = nullptr;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  std::vector<dds::Topic*> topics_;
};

}  // namespace microdex::net
