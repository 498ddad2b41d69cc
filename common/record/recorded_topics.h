#pragma once
// What a session recording holds: the schema version of the SQLite file and the DDS topics it
// records, each with its type name and the hash of the IDL file that defines the type (so a
// reader knows whether it can decode the CDR bytes). The schema: instructor/README.md.

#include <cstdint>
#include <string>
#include <vector>

namespace microdex::record {

// The version of the SQLite schema this build writes and reads (metadata "schema_version").
// A reader refuses a file with a larger version and reads every version from 1 up to this.
inline constexpr int kSchemaVersion = 1;
// metadata "format": marks the file as a microdex session recording.
inline constexpr const char* kFormatName = "microdex-session";

struct TopicInfo {
  std::string name;      // DDS topic name, e.g. "microdex/device_input"
  std::string type;      // DDS type name, e.g. "microdex::msg::DeviceInput"
  std::string idl_file;  // e.g. "device_input.idl"
  std::string idl_hash;  // XXH3-64 of that file's text, 16 lowercase hex digits
};

// Indices into KnownTopics(), in a fixed order.
enum class TopicIndex : int {
  kStationInfo,
  kDeviceInput,
  kToolState,
  kNeedleState,
  kThreadState,
  kTissueState,
  kTelemetry,
  kCueCommand,
  kTaskEvent,
  kScore,
  kCueOverlay,   // the station's visual cue overlays (60 Hz, best-effort)
  kDeviceForce,  // the device bridge's force back to an external driver (1 kHz, best-effort)
};
inline constexpr int kTopicCount = 12;

// The topics this build records, with this build's IDL hashes.
const std::vector<TopicInfo>& KnownTopics();
const TopicInfo& Topic(TopicIndex i);
// The index of a topic by name (-1: not one of ours).
int FindTopic(const std::string& name);

}  // namespace microdex::record
