#pragma once
// The station's publisher thread: owns every DDS entity of the station and waits on a
// WaitSet (the cue reader's data-available condition and a stop guard), with a timeout that
// wakes it just after each haptic tick. Each wake-up it
//   - takes cue commands addressed to this station (or "all"), checks them and hands them to
//     the haptic thread through the cue ring (rejections become TaskEvents);
//   - drains the snapshot ring: one DeviceInput per step (1 kHz, reliable keep-all), one
//     TaskEvent per cue applied (with the step it was applied at) and per contact change;
//   - publishes the mirrored states (ToolState and the cue overlay (CueOverlay), and
//   NeedleState/ThreadState/TissueState when the
//     scene has that module: their writers exist only then) at the mirror rate (thread and
//     tissue as soon as the haptic thread hands over their frame, once per mirror period),
//     Telemetry at 10 Hz and a running Score every second; recognises the thread's knot at
//     knot_rate_hz.
// Stop() publishes the last states, the final Score and a TaskEnd event, waits briefly for
// their acknowledgement, and disposes the station's StationInfo instance (its departure).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/net/dds_context.h"
#include "common/net/messages.h"
#include "common/scene/scene.h"
#include "common/view/view_frame.h"
#include "station/device.h"
#include "station/haptic_loop.h"
#include "station/period_stats.h"
#include "station/snapshot.h"

namespace eprosima::fastdds::dds {
class DataWriter;
class GuardCondition;
}  // namespace eprosima::fastdds::dds

namespace microdex::station {

struct PublisherConfig {
  std::string station_id = "station-1";
  std::string session_id;
  std::string trainee = "simulated";
  std::string device = "sim";
  double skill = -1;
  std::uint64_t seed = 1;  // the simulation's seed (StationInfo)
  // At the end, wait this long at most for the readers to acknowledge every DeviceInput.
  double input_ack_wait_s = 0.15;
  double mirror_rate_hz = 60;
  double telemetry_rate_hz = 10;
  double score_period_s = 0.5;  // live scores at 2 Hz
  double knot_rate_hz = 2;      // knot recognition of the mirrored thread (allocates: not per tick)
  bool realtime = false;
  // Wake-up this long after each tick start, to pick up its snapshot with little delay.
  std::int64_t wake_offset_ns = 60'000;
  // Called on the publisher thread with every snapshot, in step order (the audio output).
  std::function<void(const TickSnapshot&)> on_snapshot;
  // Device bridge samples refused so far (--device dds: DdsDevice::samples_invalid() of each
  // device); empty: none. Called on the publisher thread for each Telemetry.
  std::function<std::uint64_t()> device_samples_invalid;
};

// A cue as the haptic thread acknowledged it, with the step it took effect at.
struct AppliedCue {
  state::CueAck cue;
  std::uint64_t step = 0;
};

// The haptic period over one window of the run (kTicks ticks: 1 s at 1 kHz), for the score
// file's "loop.windows": what a fault did to the period is judged against the same run's other
// windows, on a host whose own scheduling noise is then the same for both.
struct PeriodWindow {
  static constexpr std::uint32_t kTicks = 1000;
  // Beyond this many windows (24 h at 1 kHz) the log stops growing; the whole-run figures go on.
  static constexpr std::size_t kMaxWindows = 86400;
  std::int64_t start_stamp_ns = 0;  // CLOCK_REALTIME of the window's first tick
  std::uint32_t ticks = 0;
  std::uint32_t overruns = 0;
  double p99_s = 0;
  double max_s = 0;
};

struct PublisherTotals {
  std::uint64_t snapshots = 0;
  std::uint64_t input_published = 0;
  std::uint64_t input_write_failed = 0;
  std::uint64_t overruns = 0;
  std::uint64_t cues_rejected = 0;
  // Of those, the invalid ones (malformed, or a parameter outside the kind's limits).
  std::uint64_t cues_invalid = 0;
  // The latest state hash the haptic thread took (once a second), and its step.
  bool has_state_hash = false;
  std::uint64_t state_hash_step = 0;
  std::uint64_t state_hash = 0;
  std::vector<AppliedCue> cues_applied;
};

class StationPublisher {
 public:
  // Creates the participant and the scene's writers (throws std::runtime_error naming the
  // profile or entity that failed) and publishes StationInfo.
  StationPublisher(const PublisherConfig& config, const net::DdsOptions& dds,
                   const scene::SceneModel& scene, StationRings& rings, const HapticLoop& loop);
  ~StationPublisher();

  // The thread body: runs until RequestStop(), then drains the ring and says goodbye.
  void Run();
  // Any thread.
  void RequestStop();
  // Before Run(): also encode a view frame (common/view) at the mirror rate into `frames`
  // (this thread is its producer; the station's view server its consumer).
  void SetViewFrames(rt::TripleBuffer<view::FrameBytes>* frames) { view_frames_ = frames; }
  // Waits until every writer of the station (StationInfo, DeviceInput, the mirrored states,
  // Telemetry, TaskEvent, Score, SceneDescription) has matched a reader (true), `timeout_s`
  // passed or `stop` is set (false; `missing` names a topic still unmatched). Call before the
  // haptic loop starts (the main thread).
  bool WaitForRecorder(double timeout_s, const std::atomic<bool>& stop, std::string* missing);
  // --wait-for-condition: takes cue commands until this run's condition has come whole (the
  // condition_size commands addressed to this station's session, CueCommand IDL): true; they
  // are then in the cue ring and apply at the first step. False after `timeout_s`, with `why`
  // naming the station and the instructor it waited for. True also when `stop` is set. Call
  // before the haptic loop and Run() start (the main thread stands in for the publisher).
  bool WaitForCondition(double timeout_s, const std::atomic<bool>& stop, std::string* why);

  const PeriodStats& run_periods() const { return run_periods_; }
  // Step time of module i over the whole run (the "period" is the step's wall time).
  const PeriodStats& run_step_times(std::size_t i) const { return run_step_times_[i]; }
  const PublisherTotals& totals() const { return totals_; }
  // The run's windows so far, the last one partial (after the final Drain: up to the last tick).
  const std::vector<PeriodWindow>& period_windows() const { return period_windows_; }
  const TickSnapshot& last() const { return last_; }
  net::Score final_score() const { return final_score_; }

 private:
  void HandleCues();
  std::vector<eprosima::fastdds::dds::DataWriter*> RecordedWriters() const;
  void Drain();
  void ClosePeriodWindow();  // the last PeriodWindow's p99 and max, from log_periods_
  void PublishMirror();
  void EncodeViewFrame();
  void PublishOverlay();
  void PublishFrames();
  void RecognizeKnot();
  void PublishTelemetry(std::int64_t now_ns);
  void PublishScore(bool is_final);
  void PublishEvent(net::TaskEventKind kind, std::uint64_t step, std::uint64_t cue_id, double value,
                    const std::string& text);
  void Goodbye();
  net::Header MakeHeader(std::uint64_t step, std::int64_t stamp_ns) const;

  PublisherConfig config_;
  const scene::SceneModel& scene_;
  StationRings& rings_;
  const HapticLoop& loop_;
  std::unique_ptr<net::DdsContext> dds_;
  std::unique_ptr<eprosima::fastdds::dds::GuardCondition> stop_guard_;
  std::atomic<bool> stop_{false};

  struct Writers;
  std::unique_ptr<Writers> w_;

  PeriodStats run_periods_;
  PeriodStats window_periods_;
  PeriodStats log_periods_;  // the open PeriodWindow's
  std::vector<PeriodWindow> period_windows_;
  std::vector<PeriodStats> run_step_times_;
  std::uint64_t window_overruns_ = 0;
  std::vector<double> window_step_time_sum_s_, window_step_time_max_s_;
  std::uint64_t window_ticks_ = 0;
  PublisherTotals totals_;
  TickSnapshot last_;
  bool have_last_ = false;
  std::uint8_t last_device_fault_ = 0;
  std::string knot_;  // "" until the first recognition
  std::vector<std::pair<std::string, std::uint64_t>> seen_cues_;
  // This run's condition (--wait-for-condition): its size, the commands received, and from
  // whom ("'ISSUER' (session S)"); the latest instructor seen sending any cue.
  std::uint32_t condition_size_ = 0, condition_received_ = 0;
  std::string condition_from_, instructor_seen_;
  std::string dds_where_;  // "DDS domain N, partition 'P'" (error messages)
  net::Score final_score_;
  rt::TripleBuffer<view::FrameBytes>* view_frames_ = nullptr;
  net::Score last_score_;  // the latest published (the view's live score)
  net::Telemetry last_telemetry_;
  bool have_score_ = false, have_telemetry_ = false;
  std::int64_t next_mirror_ns_ = 0, next_telemetry_ns_ = 0, next_score_ns_ = 0;
  std::int64_t telemetry_window_start_ns_ = 0;
};

}  // namespace microdex::station
