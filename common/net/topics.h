#pragma once
// Topic names and the XML profile names behind each (deploy/dds/*.xml). QoS is set only in
// those files; code refers to it by these names.

#include <string_view>

namespace microdex::net {

struct TopicSpec {
  const char* name;            // DDS topic name
  const char* topic_profile;   // <topic> profile (history)
  const char* writer_profile;  // <data_writer> profile
  const char* reader_profile;  // <data_reader> profile
};

inline constexpr const char* kParticipantProfile = "microdex_participant";
// The DDS device bridge's participants (the station's bridge, a driver): on one host their
// data takes shared memory (loopback.xml; a file without it: kParticipantProfile).
inline constexpr const char* kDeviceBridgeParticipantProfile = "microdex_device_bridge_participant";

inline constexpr TopicSpec kStationInfoTopic{"microdex/station_info", "microdex_topic_keep_last_1",
                                             "microdex_station_info_writer",
                                             "microdex_station_info_reader"};
inline constexpr TopicSpec kDeviceInputTopic{"microdex/device_input", "microdex_topic_keep_all",
                                             "microdex_device_input_writer",
                                             "microdex_device_input_reader"};
// The DDS device bridge: an external driver's samples (type DeviceInput, keyed by the station
// it drives) and the station's force back (DeviceForce), latest-only.
inline constexpr TopicSpec kDeviceSampleTopic{
    "microdex/device_sample", "microdex_topic_keep_last_1", "microdex_device_bridge_writer",
    "microdex_device_bridge_reader"};
inline constexpr TopicSpec kDeviceForceTopic{"microdex/device_force", "microdex_topic_keep_last_1",
                                             "microdex_device_bridge_writer",
                                             "microdex_device_bridge_reader"};
// The mirrored state topics (60 Hz) share one QoS: a reliable keep-last writer (4 s of
// samples, for a recorder), read best-effort latest-only by a console.
constexpr TopicSpec MirrorTopic(const char* name) {
  return {name, "microdex_topic_keep_last_1", "microdex_mirror_writer", "microdex_mirror_reader"};
}
inline constexpr TopicSpec kToolStateTopic = MirrorTopic("microdex/tool_state");
inline constexpr TopicSpec kNeedleStateTopic = MirrorTopic("microdex/needle_state");
inline constexpr TopicSpec kThreadStateTopic = MirrorTopic("microdex/thread_state");
inline constexpr TopicSpec kTissueStateTopic = MirrorTopic("microdex/tissue_state");
inline constexpr TopicSpec kCueOverlayTopic = MirrorTopic("microdex/cue_overlay");
// A station's scene as files, sent once (reliable, transient-local, keep-last 1 per station:
// StationInfo's QoS).
inline constexpr TopicSpec kSceneDescriptionTopic{
    "microdex/scene_description", "microdex_topic_keep_last_1", "microdex_station_info_writer",
    "microdex_station_info_reader"};
inline constexpr TopicSpec kTelemetryTopic{"microdex/telemetry", "microdex_topic_keep_last_1",
                                           "microdex_telemetry_writer",
                                           "microdex_telemetry_reader"};
inline constexpr TopicSpec kCueCommandTopic{"microdex/cue_command", "microdex_topic_cue",
                                            "microdex_cue_writer", "microdex_cue_reader"};
inline constexpr TopicSpec kTaskEventTopic{"microdex/task_event", "microdex_topic_keep_all",
                                           "microdex_events_writer", "microdex_events_reader"};
inline constexpr TopicSpec kScoreTopic{"microdex/score", "microdex_topic_keep_all",
                                       "microdex_events_writer", "microdex_events_reader"};

// The reader a recording instructor uses for `spec`: the mirrored states and the telemetry
// reliable, with a deep history (no sample lost or replaced before it is taken); the others as
// they are.
inline TopicSpec RecordingReaderSpec(TopicSpec spec) {
  const std::string_view reader = spec.reader_profile;
  if (reader == "microdex_mirror_reader") {
    spec.reader_profile = "microdex_mirror_record_reader";
  } else if (reader == "microdex_telemetry_reader") {
    spec.reader_profile = "microdex_telemetry_record_reader";
  }
  return spec;
}

}  // namespace microdex::net
