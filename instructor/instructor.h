#pragma once
// The instructor console's engine, used by microdex-instructor's text view, the tests and the
// future GUI: discovers stations (StationInfo, liveliness), mirrors each station's latest
// state per module with its age, sends cue commands to one station or all, and collects task
// events and scores.
//
// Threads: one DDS thread owns every DDS entity and waits on a WaitSet (reader conditions and
// a guard); it is the only writer of the registry. API calls from other threads read copies
// of the registry and queue cues under a mutex: the instructor has no real-time thread, so a
// short mutex is the simplest correct handoff here.

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/cues/cue_overlay.h"
#include "common/net/dds_context.h"
#include "common/net/messages.h"
#include "common/record/recorded_topics.h"
#include "common/record/recorder.h"
#include "common/view/scene_files.h"

namespace microdex::instructor {

struct InstructorOptions {
  net::DdsOptions dds;
  std::string issuer = "instructor";
  bool record_latency = false;  // keep state-latency samples (benchmark)
  // Record every sample of every station, and the cues sent, to this SQLite file from the start
  // ("": none).
  std::string record_file;
  // Read the stations' topics as a recording needs them from the start (the recording readers:
  // reliable, deep; DeviceInput and DeviceForce taken), so that StartRecording may begin a
  // recording at any time. Implied by record_file. A console that is not ready keeps the
  // lighter best-effort readers and cannot record.
  bool recording_ready = false;
  record::RecorderConfig recorder;
  // Take every station's DeviceInput (1 kHz each: counted, gaps marked) even when not
  // recording. A recording always takes them; a console without one draws the mirrored states
  // (60 Hz) and leaves the 1 kHz inputs unread, which with 8 stations is most of the
  // instructor's work and of the stations' sends.
  bool receive_inputs = false;
};

enum class Presence {
  kAlive,     // its StationInfo writer is alive (liveliness lease kept)
  kLost,      // the lease expired: the station died or its network did
  kDeparted,  // it disposed its StationInfo: a clean shutdown
};
const char* PresenceName(Presence p);

// Which signal reported a station lost (the first that fired).
enum class LossSignal {
  kNone,
  kLiveliness,  // liveliness-changed status of the StationInfo reader (writer lease or
                // participant lease expired)
  kNoWriters,   // StationInfo instance became NOT_ALIVE_NO_WRITERS (its writer was removed)
  kSilence,     // nothing received from it for kSilenceLimit_ns (second signal)
};
const char* LossSignalName(LossSignal s);

template <class T>
struct Mirror {
  std::optional<T> latest;
  std::int64_t received_ns = 0;  // monotonic, when latest arrived
  std::uint64_t count = 0;
};

// The visual cues a station draws (CueOverlay topic), as received.
struct OverlayMirror {
  net::Header header;
  std::uint32_t active_cues = 0;  // bit (1 << cues::CueKind)
  cues::CueOverlay overlay;
};

struct StationView {
  net::StationInfo info;
  Presence presence = Presence::kAlive;
  std::int64_t presence_changed_ns = 0;    // monotonic
  int comebacks = 0;                       // times it became alive again after lost/departed
  LossSignal lost_by = LossSignal::kNone;  // of the latest loss (kNone while never lost)
  std::int64_t last_heard_ns = 0;          // monotonic, last sample of any topic from it
  Mirror<net::ToolState> tool;
  Mirror<net::NeedleState> needle;
  Mirror<net::ThreadState> thread;
  Mirror<net::TissueState> tissue;
  Mirror<net::Telemetry> telemetry;
  Mirror<net::Score> score;
  bool inputs_taken = false;  // DeviceInput read (recording or receive_inputs)
  std::uint64_t inputs_received = 0;
  std::uint64_t inputs_lost = 0;  // gaps in the DeviceInput step sequence of a session
  std::uint64_t last_input_step = 0;
  std::string input_session;
  Mirror<OverlayMirror> overlay;
  std::deque<net::TaskEvent> events;  // the latest kMaxEventsPerStation
  // The scene's files (SceneDescription topic) once received and checked
  // (view::CheckSceneFiles); shared, never changed once set. scene_error: why the latest
  // description was refused ("" when none was).
  std::shared_ptr<const view::SceneFiles> scene_files;
  std::string scene_error;
};

// Missing DeviceInput steps of one station's run, seen when its steps resumed (a partition
// longer than the DDS lease, a writer history overflow). Also written to the recording's
// metadata ("input_gaps", instructor/README.md "Recording").
struct InputGap {
  std::string station_id;
  std::string session_id;
  std::uint64_t first_missing_step = 0;
  std::uint64_t last_missing_step = 0;
  std::int64_t receive_ns = 0;  // CLOCK_REALTIME, when the first step after the gap arrived
};

// Received samples dropped before use: invalid (FromMsg's reason) or from a station beyond
// kMaxStations. By topic ("device_input", "tool_state", ...).
struct RejectedSamples {
  std::map<std::string, std::uint64_t> by_topic;
  std::uint64_t total = 0;
  std::string last_reason;  // "TOPIC: reason" of the latest
};

struct LatencySamples {
  std::vector<double> state_age_us;  // receive − stamp_ns (tick start of the state)
  std::vector<double> transport_us;  // receive − the writer's source timestamp
  std::map<std::string, std::vector<double>> state_age_us_by_topic;  // "tool_state", ...
};

class Instructor {
 public:
  static constexpr std::size_t kMaxEventsPerStation = 256;
  // A live station publishes DeviceInput at 1 kHz and Telemetry at 10 Hz: silence for this
  // long marks it lost even if no liveliness change named it. A second signal only: the
  // participant lease (1 s, deploy/dds) makes the liveliness path report a killed station
  // first (0.75-1 s after the kill), so this is set longer than that.
  static constexpr std::int64_t kSilenceLimit_ns = 1'500'000'000;
  // Stations the registry admits (the DeviceInput reader's max_instances, deploy/dds): a
  // sample naming a new station beyond this is dropped and counted, so that a hostile
  // participant cannot grow the registry without bound.
  static constexpr std::size_t kMaxStations = 64;
  // Writers whose station the DDS thread keeps (FromItsStation); cleared and filled again
  // when more.
  static constexpr std::size_t kMaxWriterCache = 4096;
  static constexpr std::int64_t kRejectedRecordPeriod_ns = 500'000'000;

  // Creates the participant (throws std::runtime_error naming the profile) and starts the
  // DDS thread.
  explicit Instructor(const InstructorOptions& options);
  ~Instructor();
  Instructor(const Instructor&) = delete;
  Instructor& operator=(const Instructor&) = delete;

  // Copies of the registry, sorted by station id.
  std::vector<StationView> Stations() const;
  std::optional<StationView> Station(const std::string& station_id) const;
  // Calls f with every station in id order under the registry's lock, without copying (the
  // console's poll): f must be quick and must not call back into the Instructor.
  void VisitStations(const std::function<void(const StationView&)>& f) const;

  // Queues a cue for `station_id` (or net::kAllStations) applied at `at_step` (0: on
  // receipt); `off` switches the kind off. Returns its cue id. Throws std::invalid_argument
  // for a bad target.
  std::uint64_t SendCue(const std::string& station_id, cues::CueKind kind, double param,
                        std::uint64_t at_step = 0, bool off = false);
  // A trial's condition for one run of a station (`station_session`, its StationInfo's
  // session id): its cues, or for a condition without any an explicit "no cue" (one `clear`),
  // each sent as one of the condition's commands (CueCommand.condition_size), on receipt, so
  // that a station started with --wait-for-condition knows when it has them all and applies
  // them from step 0. Returns their cue ids. Throws std::invalid_argument for a bad target or
  // more than net::kMaxConditionSize cues.
  std::vector<std::uint64_t> SendCondition(const std::string& station_id,
                                           const std::string& station_session,
                                           const std::vector<cues::CueArg>& cues);

  // Task events of every station received since the last call, in arrival order.
  std::vector<net::TaskEvent> TakeEvents();

  // The final scores received since the last call (every one, even when a station's next
  // session has replaced it in the registry's mirror), in arrival order.
  std::vector<net::Score> TakeFinalScores();

  // Latency samples so far (record_latency only); clears them.
  LatencySamples TakeLatency();

  std::string session_id() const { return session_id_; }

  // Samples dropped before use so far.
  RejectedSamples Rejected() const;
  // DeviceInput gaps seen so far, in arrival order.
  std::vector<InputGap> InputGaps() const;

  // The recorder's counters; nullopt while not recording.
  std::optional<record::RecorderStats> RecorderStats() const;
  // Writes what the recorder holds, with the rejected counts so far, and waits for the commit
  // (nothing while not recording).
  void FlushRecording();

  bool recording_ready() const { return ready_; }
  // Starts recording into a new SQLite file at `path`: first the StationInfo of every station
  // alive now (so that a replay announces them), then every sample as it arrives. Throws
  // std::logic_error when the console is not recording-ready or already records,
  // std::runtime_error "PATH: reason" when the file cannot be created (an existing file is
  // never overwritten).
  void StartRecording(const std::string& path);
  // Ends the recording: writes what is queued, with the rejected counts and input gaps, closes
  // the file and returns its final counters (nullopt when none was running).
  std::optional<record::RecorderStats> StopRecording();
  // The file being recorded ("" while not recording) and when it began (CLOCK_MONOTONIC, ns).
  std::string RecordingPath() const;
  std::int64_t RecordingStartedNs() const;

 private:
  struct Dds;
  void Run();
  void HandleStationInfo();
  void HandleLiveliness();
  // Takes the next sample of `reader` (a dds::DataReader) into `m` and `si`, at most
  // kTakeBatch per reader and pass of Run(): a reader with more left marks a backlog, and
  // the next pass comes at once.
  bool TakeNext(void* reader, void* m, void* si, int& taken);
  template <class Msg, class Plain>
  void TakeAll(void* reader, Mirror<Plain> StationView::*mirror, const char* topic);
  // Takes every sample of a topic only recorded (no mirror): DeviceForce. `name`: the
  // topic's name for the rejected counts ("device_force").
  template <class Msg>
  void RecordOnly(void* reader, record::TopicIndex topic, const char* name);
  void HandleInputs();
  void HandleEvents();
  void HandleScores();
  void HandleSceneDescriptions();
  void HandleOverlays();
  void SendQueuedCues();
  void CheckSilence();
  // The rejected counts into the recording's metadata when they changed (recording only):
  // at most every kRejectedRecordPeriod_ns unless `now`.
  void RecordRejected(bool now);
  // Hands the sample to the recorder (serialized again to CDR with its type); DDS thread only.
  template <class Msg>
  void Record(int topic, Msg& m, const void* sample_info);
  StationView& ViewFor(const std::string& station_id);
  // With per-station partitions (a secure instructor's COURSE/*): true when the writer that
  // sent the sample (its SampleInfo) publishes in partition COURSE/station_id (or, with
  // second_device_key, station_id is that station's second device key STATION/2); otherwise
  // counts it rejected. Always true without them. DDS thread only; takes mutex_ to reject.
  bool FromItsStation(const void* sample_info, const char* station_id, const char* topic,
                      bool second_device_key = false);
  // Counts a dropped sample (mutex_ held).
  void Reject(const char* topic, const std::string& why);
  // True when a valid sample from station_id may be used: the station is known or the
  // registry has room; otherwise counts it rejected. Takes mutex_.
  bool Admit(const std::string& station_id, const char* topic);
  // A sample from v arrived: a station lost by silence or liveliness (not by its writers'
  // removal) is alive again (mutex_ held).
  static void Heard(StationView& v, std::int64_t now_ns);
  // Marks v lost by `signal` if it is alive (mutex_ held).
  static void MarkLost(StationView& v, LossSignal signal, std::int64_t now_ns);

  InstructorOptions options_;
  bool ready_ = false;  // recording_ready or record_file
  std::string session_id_;
  // The running recording, if any; swapped by StartRecording / StopRecording on any thread,
  // pushed to by the DDS thread, under recorder_mutex_ (taken after mutex_ when both are).
  mutable std::mutex recorder_mutex_;
  std::shared_ptr<record::Recorder> recorder_;  // before dds_: outlives the DDS thread
  std::atomic<std::int64_t> recording_started_ns_{0};
  std::atomic<std::int64_t> recording_started_realtime_ns_{0};
  std::atomic<bool> recording_{false};  // recorder_ set: the DDS thread's test without the lock
  // The latest StationInfo of each station as recorded (recording-ready only), for the start of
  // a recording begun later (recorder_mutex_).
  std::map<std::string, record::RecordedMessage> latest_info_;
  std::shared_ptr<record::Recorder> CurrentRecorder() const;
  std::unique_ptr<Dds> dds_;
  std::atomic<bool> stop_{false};
  bool backlog_ = false;  // DDS thread: a reader had more than one pass's batch
  std::atomic<std::uint64_t> next_cue_id_{1};

  mutable std::mutex mutex_;  // guards everything below
  std::map<std::string, StationView> stations_;
  std::map<std::string, std::string> writer_to_station_;  // StationInfo writer GUID → id
  std::vector<net::TaskEvent> new_events_;
  std::vector<net::Score> final_scores_;
  std::vector<net::CueCommand> queued_cues_;
  LatencySamples latency_;
  RejectedSamples rejected_;
  std::uint64_t rejected_recorded_ = 0;  // rejected_.total when last put in the metadata
  std::int64_t next_rejected_record_ns_ = 0;
  std::vector<InputGap> gaps_;

  std::thread thread_;
};

// The text view: one line per station.
std::string FormatStationTable(const std::vector<StationView>& stations, std::int64_t now_ns);

// "rejected N received samples: TOPIC n, ... (latest: TOPIC: reason)" ("" when none).
std::string FormatRejected(const RejectedSamples& rejected);

// The recording's "rejected_samples" metadata: one line per topic, "TOPIC COUNT".
std::string FormatRejectedMetadata(const RejectedSamples& rejected);

// The recording's "input_gaps" metadata: one line per gap, "STATION SESSION FIRST_MISSING_STEP
// LAST_MISSING_STEP RECEIVE_NS"; only the gaps received at or after from_realtime_ns.
std::string FormatInputGaps(const std::vector<InputGap>& gaps, std::int64_t from_realtime_ns = 0);

// CLOCK_MONOTONIC now, ns (the clock of the *_ns fields above).
std::int64_t MonotonicNowNs();

}  // namespace microdex::instructor
