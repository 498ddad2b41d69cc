#include "common/net/dds_context.h"

#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <filesystem>
#include <mutex>
#include <stdexcept>

#include "common/net/dds_security.h"

namespace microdex::net {
namespace {

using eprosima::fastrtps::types::ReturnCode_t;

#ifndef MICRODEX_SOURCE_DIR
#define MICRODEX_SOURCE_DIR "."
#endif

// Loads the profile file into the process-wide factory once. A second context with another
// file is refused: Fast DDS keeps one set of profile names per process.
void LoadProfilesOnce(const std::string& file) {
  static std::mutex mutex;
  static std::string loaded;
  std::lock_guard<std::mutex> lock(mutex);
  const std::string canonical = std::filesystem::weakly_canonical(file).string();
  if (!loaded.empty()) {
    if (loaded != canonical) {
      throw std::runtime_error("dds profile '" + file + "': another profile file ('" + loaded +
                               "') is already loaded in this process");
    }
    return;
  }
  if (!std::filesystem::is_regular_file(file)) {
    throw std::runtime_error("dds profile '" + file + "': no such file");
  }
  // Fast DDS also loads $FASTRTPS_DEFAULT_PROFILES_FILE and ./DEFAULT_FASTRTPS_PROFILES.xml
  // when the factory first needs profiles; pointing both at the chosen file makes it the only
  // source of profiles, so the two cannot define the same names differently.
  setenv("FASTRTPS_DEFAULT_PROFILES_FILE", canonical.c_str(), 1);
  setenv("SKIP_DEFAULT_XML_FILE", "1", 1);
  auto* factory = dds::DomainParticipantFactory::get_instance();
  if (factory->load_profiles() != ReturnCode_t::RETCODE_OK) {
    throw std::runtime_error("dds profile '" + file + "': Fast DDS could not parse it");
  }
  dds::DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(kParticipantProfile, qos) !=
      ReturnCode_t::RETCODE_OK) {
    throw std::runtime_error("dds profile '" + file + "': no participant profile '" +
                             kParticipantProfile + "'");
  }
  loaded = canonical;
}

// The entity, or the error naming the profile file, the entity and its profile.
template <typename Entity>
Entity* CreatedFromProfile(Entity* entity, const std::string& profile_file, const char* kind,
                           const std::string& name, const std::string& profile) {
  if (entity == nullptr) {
    throw std::runtime_error("dds profile '" + profile_file + "': cannot create " + kind + " " +
                             name + " from profile '" + profile + "'");
  }
  return entity;
}

}  // namespace

std::string DdsOptions::Validate() const {
  if (profile_file.empty()) return "dds-profile: empty path";
  if (domain_id < 0 || domain_id > 232) return "domain: expected 0..232";
  if (partition.size() > 64) return "partition: longer than 64 characters";
  for (char ch : partition) {
    if (ch == '*' || ch == '?' || ch == '[' || ch == ']' || ch == '\\') {
      return "partition: no wildcard characters (*?[]\\) allowed";
    }
  }
  return {};
}

std::string DefaultDdsProfileFile() {
  if (const char* env = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE"); env != nullptr && *env) {
    return env;
  }
  std::string local = "deploy/dds/loopback.xml";
  if (std::filesystem::is_regular_file(local)) return local;
  return std::string(MICRODEX_SOURCE_DIR) + "/deploy/dds/loopback.xml";
}

DdsContext::DdsContext(const DdsOptions& options) : options_(options) {
  if (std::string why = options_.Validate(); !why.empty()) throw std::runtime_error(why);
  LoadProfilesOnce(options_.profile_file);
  auto* factory = dds::DomainParticipantFactory::get_instance();
  const auto domain = static_cast<dds::DomainId_t>(options_.domain_id);
  partition_ = options_.partition;
  participant_profile_ = kParticipantProfile;
  if (dds::DomainParticipantQos probe;
      !options_.participant_profile.empty() &&
      factory->get_participant_qos_from_profile(options_.participant_profile, probe) ==
          ReturnCode_t::RETCODE_OK) {
    participant_profile_ = options_.participant_profile;
  }
  if (options_.security_dir.empty()) {
    participant_ = factory->create_participant_with_profile(
        domain, participant_profile_, options_.participant_listener, dds::StatusMask::none());
  } else {
    const SecurityFiles files = LoadSecurityFiles(options_.security_dir);
    if (!options_.partition.empty() && options_.partition != files.course) {
      throw std::runtime_error("security '" + files.dir + "': its course is '" + files.course +
                               "', not the partition '" + options_.partition + "'");
    }
    partition_ = SecurePartition(files.course, options_.security_station);
    // The participant profile's QoS as create_participant_with_profile builds it (the
    // factory's default QoS with the profile's attributes), plus the security properties.
    dds::DomainParticipantQos qos;
    if (factory->get_participant_qos_from_profile(participant_profile_, qos) !=
        ReturnCode_t::RETCODE_OK) {
      throw std::runtime_error("dds profile '" + options_.profile_file +
                               "': no participant profile '" + participant_profile_ + "'");
    }
    for (const auto& [name, value] : SecurityProperties(files)) {
      qos.properties().properties().emplace_back(name, value);
    }
    participant_ = factory->create_participant(domain, qos, options_.participant_listener,
                                               dds::StatusMask::none());
    if (participant_ == nullptr) {
      throw std::runtime_error(
          "security '" + files.dir + "': Fast DDS refused the secure participant on domain " +
          std::to_string(options_.domain_id) +
          " (its files verify; is the certificate or the permissions grant out of its validity "
          "period, or the grant's subject not cert.pem's?)");
    }
  }
  if (participant_ == nullptr) {
    throw std::runtime_error("dds profile '" + options_.profile_file +
                             "': cannot create a participant on domain " +
                             std::to_string(options_.domain_id));
  }
  dds::PublisherQos pub_qos = participant_->get_default_publisher_qos();
  dds::SubscriberQos sub_qos = participant_->get_default_subscriber_qos();
  if (!partition_.empty()) {
    pub_qos.partition().push_back(partition_.c_str());
    sub_qos.partition().push_back(partition_.c_str());
  }
  publisher_ = participant_->create_publisher(pub_qos);
  subscriber_ = participant_->create_subscriber(sub_qos);
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    throw std::runtime_error("dds: cannot create publisher/subscriber");
  }
}

DdsContext::~DdsContext() {
  if (participant_ == nullptr) return;
  participant_->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

dds::Topic* DdsContext::GetTopicImpl(const TopicSpec& spec, dds::TypeSupport (*make_type)()) {
  for (dds::Topic* t : topics_) {
    if (t->get_name() == spec.name) return t;
  }
  dds::TypeSupport type = make_type();
  if (participant_->find_type(type.get_type_name()).empty()) {
    if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
      throw std::runtime_error(std::string("dds: cannot register type ") + type.get_type_name());
    }
  }
  dds::Topic* topic = CreatedFromProfile(
      participant_->create_topic_with_profile(spec.name, type.get_type_name(), spec.topic_profile),
      options_.profile_file, "topic", spec.name, spec.topic_profile);
  topics_.push_back(topic);
  return topic;
}

dds::DataWriter* DdsContext::CreateWriterImpl(dds::Topic* topic, const TopicSpec& spec) {
  dds::DataWriter* writer = publisher_->create_datawriter_with_profile(topic, spec.writer_profile);
  if (writer == nullptr && !options_.security_dir.empty()) {
    throw std::runtime_error("security '" + options_.security_dir +
                             "': permissions.p7s grants no "
                             "publishing of " +
                             spec.name + " in partition '" + partition_ + "'");
  }
  return CreatedFromProfile(writer, options_.profile_file, "writer", spec.name,
                            spec.writer_profile);
}

void DdsContext::DeleteWriter(dds::DataWriter* writer) {
  if (writer != nullptr) publisher_->delete_datawriter(writer);
}

dds::DataReader* DdsContext::CreateReaderImpl(dds::Topic* topic, const TopicSpec& spec) {
  dds::DataReader* reader = subscriber_->create_datareader_with_profile(topic, spec.reader_profile);
  if (reader == nullptr && !options_.security_dir.empty()) {
    throw std::runtime_error("security '" + options_.security_dir +
                             "': permissions.p7s grants no "
                             "subscribing to " +
                             spec.name + " in partition '" + partition_ + "'");
  }
  return CreatedFromProfile(reader, options_.profile_file, "reader", spec.name,
                            spec.reader_profile);
}

}  // namespace microdex::net
