#pragma once
// Topic names and the XML profile names behind each (deploy/dds/*.xml). QoS is set only in
// those files; code refers to it by these names.

namespace microdex::net {

struct TopicSpec {
  const char* name;            // DDS topic name
  const char* topic_profile;   // <topic> profile (history)
  const char* writer_profile;  // <data_writer> profile
  const char* reader_profile;  // <data_reader> profile
};

inline constexpr const char* kParticipantProfile = "microdex_participant";

inline constexpr TopicSpec kStationInfoTopic{"microdex/station_info", "microdex_topic_keep_last_1",
                                             "microdex_station_info_writer",
                                             "microdex_station_info_reader"};
inline constexpr TopicSpec kDeviceInputTopic{"microdex/device_input", "microdex_topic_keep_all",
                                             "microdex_device_input_writer",
                                             "microdex_device_input_reader"};
// The recording instructor's DeviceInput reader: transient-local, to get each station's
// samples from step 0 out of the writer's history (deploy/dds: the writer keeps 10 s).
inline constexpr TopicSpec kDeviceInputRecordTopic{
    "microdex/device_input", "microdex_topic_keep_all", "microdex_device_input_writer",
    "microdex_device_input_record_reader"};
// The mirrored state topics (60 Hz, the latest sample is all a mirror needs) share one QoS.
constexpr TopicSpec MirrorTopic(const char* name) {
  return {name, "microdex_topic_keep_last_1", "microdex_mirror_writer", "microdex_mirror_reader"};
}
inline constexpr TopicSpec kToolStateTopic = MirrorTopic("microdex/tool_state");
inline constexpr TopicSpec kNeedleStateTopic = MirrorTopic("microdex/needle_state");
inline constexpr TopicSpec kThreadStateTopic = MirrorTopic("microdex/thread_state");
inline constexpr TopicSpec kTissueStateTopic = MirrorTopic("microdex/tissue_state");
inline constexpr TopicSpec kCueOverlayTopic = MirrorTopic("microdex/cue_overlay");
inline constexpr TopicSpec kTelemetryTopic{"microdex/telemetry", "microdex_topic_keep_last_1",
                                           "microdex_telemetry_writer",
                                           "microdex_telemetry_reader"};
inline constexpr TopicSpec kCueCommandTopic{"microdex/cue_command", "microdex_topic_cue",
                                            "microdex_cue_writer", "microdex_cue_reader"};
inline constexpr TopicSpec kTaskEventTopic{"microdex/task_event", "microdex_topic_keep_all",
                                           "microdex_events_writer", "microdex_events_reader"};
inline constexpr TopicSpec kScoreTopic{"microdex/score", "microdex_topic_keep_all",
                                       "microdex_events_writer", "microdex_events_reader"};

}  // namespace microdex::net
