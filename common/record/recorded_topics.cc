#include "common/record/recorded_topics.h"

#include <cstdio>
#include <cstring>

#include "common/base/check.h"
#include "common/record/idl_hashes.h"

namespace microdex::record {
namespace {

std::string HashOf(const char* stem) {
  for (const IdlFileHash& h : kIdlFileHashes) {
    if (std::strcmp(h.stem, stem) == 0) {
      char hex[24];
      std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h.xxh3));
      return hex;
    }
  }
  MICRODEX_CHECK(false && "an IDL file without a hash");
  return {};
}

TopicInfo Make(const char* topic, const char* type, const char* stem) {
  return {topic, std::string("microdex::msg::") + type, std::string(stem) + ".idl", HashOf(stem)};
}

}  // namespace

const std::vector<TopicInfo>& KnownTopics() {
  // The topic names are those of common/net/topics.h (kept free of DDS here); the recorder's
  // test checks that they agree.
  static const std::vector<TopicInfo> topics = {
      Make("microdex/station_info", "StationInfo", "station_info"),
      Make("microdex/device_input", "DeviceInput", "device_input"),
      Make("microdex/tool_state", "ToolState", "tool_state"),
      Make("microdex/needle_state", "NeedleState", "needle_state"),
      Make("microdex/thread_state", "ThreadState", "thread_state"),
      Make("microdex/tissue_state", "TissueState", "tissue_state"),
      Make("microdex/telemetry", "Telemetry", "telemetry"),
      Make("microdex/cue_command", "CueCommand", "cue_command"),
      Make("microdex/task_event", "TaskEvent", "task_event"),
      Make("microdex/score", "Score", "score"),
      Make("microdex/cue_overlay", "CueOverlay", "cue_overlay"),
      Make("microdex/device_force", "DeviceForce", "device_force"),
  };
  return topics;
}

const TopicInfo& Topic(TopicIndex i) { return KnownTopics()[static_cast<std::size_t>(i)]; }

int FindTopic(const std::string& name) {
  const auto& t = KnownTopics();
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace microdex::record
