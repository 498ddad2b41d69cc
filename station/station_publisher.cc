#include "station/station_publisher.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <thread>

#include "common/knot/recognition.h"
#include "common/net/convert.h"
#include "common/net/overlay_convert.h"
#include "common/view/scene_description_msg.h"
#include "common/view/scene_files.h"
#include "cue_commandPubSubTypes.h"
#include "cue_overlayPubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "needle_statePubSubTypes.h"
#include "scene_descriptionPubSubTypes.h"
#include "scorePubSubTypes.h"
#include "station/rt/clock.h"
#include "station/score.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"
#include "tool_statePubSubTypes.h"

namespace microdex::station {

static_assert(kMaxFrameThreadNodes == net::kMaxThreadNodes, "frame bound = ThreadState bound");
static_assert(kMaxFrameTissueNodes == net::kMaxTissueNodes, "frame bound = TissueState bound");

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

struct StationPublisher::Writers {
  dds::DataWriter* info = nullptr;
  dds::DataWriter* scene = nullptr;  // SceneDescription, written once
  dds::DataWriter* input = nullptr;
  dds::DataWriter* tool = nullptr;
  dds::DataWriter* needle = nullptr;  // only with the needle module
  dds::DataWriter* thread = nullptr;  // only with the thread module
  dds::DataWriter* tissue = nullptr;  // only with the tissue module
  dds::DataWriter* overlay = nullptr;
  dds::DataWriter* telemetry = nullptr;
  dds::DataWriter* events = nullptr;
  dds::DataWriter* score = nullptr;
  dds::DataReader* cues = nullptr;
  dds::WaitSet waitset;
  msg::StationInfo info_msg;
  eprosima::fastrtps::rtps::InstanceHandle_t info_handle;
  msg::DeviceInput input_msg;
  msg::ToolState tool_msg;
  msg::NeedleState needle_msg;
  msg::ThreadState thread_msg;
  msg::TissueState tissue_msg;
  msg::CueOverlay overlay_msg;
  cues::CueOverlay overlay_plain;
  msg::Telemetry telemetry_msg;
  msg::TaskEvent event_msg;
  msg::Score score_msg;
  msg::CueCommand cue_msg;
  net::DeviceInput input_plain;
  net::ToolState tool_plain;
  net::NeedleState needle_plain;
  net::ThreadState thread_plain;
  net::TissueState tissue_plain;
};

namespace {

rt::MonotonicClock& SystemClock() {
  static rt::MonotonicClock clock;
  return clock;
}

Eigen::Vector3d E(const Vec3& v) { return {v[0], v[1], v[2]}; }
Eigen::Quaterniond Q(const Quat& q) { return {q[0], q[1], q[2], q[3]}; }

// The geometry's clearance status as the message's, enumerator by enumerator.
net::ClearanceStatus ToNet(geometry::ClearanceStatus status) {
  switch (status) {
    case geometry::ClearanceStatus::kOk:
      return net::ClearanceStatus::kOk;
    case geometry::ClearanceStatus::kEmptyRange:
      return net::ClearanceStatus::kEmptyRange;
    case geometry::ClearanceStatus::kInvalidInput:
      return net::ClearanceStatus::kInvalidInput;
  }
  return net::ClearanceStatus::kInvalidInput;
}

// The tissue step's status as the message's, enumerator by enumerator.
net::TissueStepStatus ToNet(fem::TissueStatus status) {
  switch (status) {
    case fem::TissueStatus::kOk:
      return net::TissueStepStatus::kOk;
    case fem::TissueStatus::kNoContact:
      return net::TissueStepStatus::kNoContact;
    case fem::TissueStatus::kBadInput:
      return net::TissueStepStatus::kBadInput;
    case fem::TissueStatus::kTooManyContacts:
      return net::TissueStepStatus::kTooManyContacts;
    case fem::TissueStatus::kNotConverged:
      return net::TissueStepStatus::kNotConverged;
    case fem::TissueStatus::kFactorisationFailed:
      return net::TissueStepStatus::kFactorisationFailed;
    case fem::TissueStatus::kNonFinite:
      return net::TissueStepStatus::kNonFinite;
  }
  return net::TissueStepStatus::kNonFinite;
}

}  // namespace

StationPublisher::StationPublisher(const PublisherConfig& config, const net::DdsOptions& dds,
                                   const scene::SceneModel& scene, StationRings& rings,
                                   const HapticLoop& loop)
    : config_(config),
      scene_(scene),
      rings_(rings),
      loop_(loop),
      dds_(std::make_unique<net::DdsContext>(dds)),
      stop_guard_(std::make_unique<dds::GuardCondition>()),
      w_(std::make_unique<Writers>()),
      dds_where_("DDS domain " + std::to_string(dds.domain_id) +
                 (dds.partition.empty() ? std::string() : ", partition '" + dds.partition + "'")) {
  w_->info = dds_->CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  w_->input = dds_->CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceInputTopic);
  w_->tool = dds_->CreateWriter<msg::ToolStatePubSubType>(net::kToolStateTopic);
  w_->overlay = dds_->CreateWriter<msg::CueOverlayPubSubType>(net::kCueOverlayTopic);
  // Only the scene's modules' topics.
  if (scene.HasModule("needle")) {
    w_->needle = dds_->CreateWriter<msg::NeedleStatePubSubType>(net::kNeedleStateTopic);
  }
  if (scene.HasModule("thread")) {
    w_->thread = dds_->CreateWriter<msg::ThreadStatePubSubType>(net::kThreadStateTopic);
    w_->thread_plain.nodes.reserve(kMaxFrameThreadNodes);
  }
  if (scene.HasModule("tissue")) {
    w_->tissue = dds_->CreateWriter<msg::TissueStatePubSubType>(net::kTissueStateTopic);
    w_->tissue_plain.displacement_m.reserve(kMaxFrameTissueNodes);
    const scene::TissueSceneDef& t = *scene.tissue;
    w_->tissue_plain.p_WS = t.X_WS.translation();
    w_->tissue_plain.q_WS = Eigen::Quaterniond(t.X_WS.linear());
    w_->tissue_plain.length_x_m = t.def.length_x_m;
    w_->tissue_plain.length_y_m = t.def.length_y_m;
  }
  w_->telemetry = dds_->CreateWriter<msg::TelemetryPubSubType>(net::kTelemetryTopic);
  w_->events = dds_->CreateWriter<msg::TaskEventPubSubType>(net::kTaskEventTopic);
  w_->score = dds_->CreateWriter<msg::ScorePubSubType>(net::kScoreTopic);
  w_->cues = dds_->CreateReader<msg::CueCommandPubSubType>(net::kCueCommandTopic);
  w_->cues->get_statuscondition().set_enabled_statuses(dds::StatusMask::data_available());
  w_->waitset.attach_condition(w_->cues->get_statuscondition());
  w_->waitset.attach_condition(*stop_guard_);
  window_step_time_sum_s_.assign(scene.modules.size(), 0.0);
  window_step_time_max_s_.assign(scene.modules.size(), 0.0);
  run_step_times_.resize(scene.modules.size());
  final_score_.header.station_id = config_.station_id;

  net::StationInfo info;
  info.header = MakeHeader(0, SystemClock().RealtimeNs());
  info.trainee = config_.trainee;
  info.scene = scene.path;
  info.modules = scene.modules;
  info.build = MICRODEX_BUILD_VERSION;
  info.haptic_rate_hz = scene.haptic.rate_hz;
  info.mirror_rate_hz = config_.mirror_rate_hz;
  info.skill = config_.skill;
  info.device = config_.device;
  info.seed = config_.seed;
  // The scene's files for a remote instructor's mirror: once, before StationInfo names their
  // hash (a scene parsed from text has no files: no description, hash 0).
  if (!scene.path.empty()) {
    try {
      const view::SceneFiles files = view::CollectSceneFiles(scene);
      msg::SceneDescription d = view::ToSceneDescription(files, config_.station_id,
                                                         config_.session_id, info.header.stamp_ns);
      w_->scene = dds_->CreateWriter<msg::SceneDescriptionPubSubType>(net::kSceneDescriptionTopic);
      if (w_->scene->write(&d)) {
        info.scene_hash = files.hash;
      } else {
        spdlog::warn("station {}: the scene description could not be written", config_.station_id);
      }
    } catch (const std::exception& e) {
      spdlog::warn("station {}: no scene description: {}", config_.station_id, e.what());
    }
  }
  net::ToMsg(info, w_->info_msg);
  w_->info_handle = w_->info->register_instance(&w_->info_msg);
  w_->info->write(&w_->info_msg, w_->info_handle);
}

StationPublisher::~StationPublisher() {
  if (w_) {
    w_->waitset.detach_condition(*stop_guard_);
    w_->waitset.detach_condition(w_->cues->get_statuscondition());
  }
  w_.reset();
  dds_.reset();  // deletes the participant and everything in it
}

net::Header StationPublisher::MakeHeader(std::uint64_t step, std::int64_t stamp_ns) const {
  return {config_.station_id, config_.session_id, step, stamp_ns};
}

std::vector<dds::DataWriter*> StationPublisher::RecordedWriters() const {
  std::vector<dds::DataWriter*> out;
  for (dds::DataWriter* w : {w_->info, w_->scene, w_->input, w_->tool, w_->overlay, w_->needle,
                             w_->thread, w_->tissue, w_->telemetry, w_->events, w_->score}) {
    if (w != nullptr) out.push_back(w);
  }
  return out;
}

bool StationPublisher::WaitForRecorder(double timeout_s, const std::atomic<bool>& stop,
                                       std::string* missing) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    // DeviceInput first (only an instructor reads it), then every other writer: each matches
    // the instructor's reader on its own, and a sample written before its match is not
    // delivered (volatile), nor is the final score of a writer that never matched.
    std::string unmatched;
    for (dds::DataWriter* w : RecordedWriters()) {
      dds::PublicationMatchedStatus status;
      w->get_publication_matched_status(status);
      if (status.current_count > 0) continue;
      unmatched = w->get_topic()->get_name();
      if (w == w_->input) break;
    }
    if (unmatched.empty()) return true;
    if (stop.load() || std::chrono::steady_clock::now() >= deadline) {
      if (missing != nullptr) *missing = unmatched;
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

bool StationPublisher::WaitForCondition(double timeout_s, const std::atomic<bool>& stop,
                                        std::string* why) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  dds::ConditionSeq active;
  for (;;) {
    HandleCues();
    if (condition_size_ > 0 && condition_received_ >= condition_size_) return true;
    if (stop.load()) return true;  // stopping anyway: no error
    if (std::chrono::steady_clock::now() >= deadline) break;
    w_->waitset.wait(active, eprosima::fastrtps::Duration_t(0, 50'000'000));
  }
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%g", timeout_s);
  std::string text = "station '" + config_.station_id + "' (session " + config_.session_id +
                     "): --wait-for-condition " + seconds + ": no condition for this run ";
  if (condition_size_ > 0) {
    text += "from instructor " + condition_from_ + " within " + seconds +
            " s: " + std::to_string(condition_received_) + " of its " +
            std::to_string(condition_size_) + " commands received";
  } else {
    dds::SubscriptionMatchedStatus matched;
    w_->cues->get_subscription_matched_status(matched);
    text += std::string("within ") + seconds + " s from ";
    if (!instructor_seen_.empty()) {
      text += "instructor " + instructor_seen_ +
              " (it sent cues to other stations: is this station's trainee in its experiment, "
              "and does the station run its scene?)";
    } else if (matched.current_count > 0) {
      text += "the instructor whose cue writer matched on " + dds_where_ +
              " (it sent no command: is it running an experiment, --experiment?)";
    } else {
      text += "an instructor: none found on " + dds_where_ +
              " (no cue writer matched; start microdex-instructor --experiment first)";
    }
  }
  if (why != nullptr) *why = text;
  return false;
}

void StationPublisher::RequestStop() {
  stop_.store(true);
  stop_guard_->set_trigger_value(true);
}

void StationPublisher::PublishEvent(net::TaskEventKind kind, std::uint64_t step,
                                    std::uint64_t cue_id, double value, const std::string& text) {
  net::TaskEvent e;
  e.header = MakeHeader(step, SystemClock().RealtimeNs());
  e.kind = kind;
  e.cue_id = cue_id;
  e.value = value;
  e.text = text.substr(0, 128);
  net::ToMsg(e, w_->event_msg);
  w_->events->write(&w_->event_msg);
}

void StationPublisher::HandleCues() {
  dds::SampleInfo info;
  while (w_->cues->take_next_sample(&w_->cue_msg, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    net::CueCommand cue;
    std::string why;
    if (!net::FromMsg(w_->cue_msg, cue, &why)) {
      ++totals_.cues_rejected;
      ++totals_.cues_invalid;
      PublishEvent(net::TaskEventKind::kCueRejected, last_.step, w_->cue_msg.cue_id(), 0,
                   "malformed cue: " + why);
      continue;
    }
    const std::string from = "'" + cue.issuer + "' (session " + cue.header.session_id + ")";
    instructor_seen_ = from;
    if (cue.header.station_id != config_.station_id && cue.header.station_id != net::kAllStations) {
      continue;  // addressed to another station
    }
    if (!cue.station_session.empty() && cue.station_session != config_.session_id) {
      continue;  // for another run of this station (transient-local history keeps them)
    }
    // A cue is applied once, even when transient-local history delivers it again.
    const auto key = std::make_pair(cue.issuer + "/" + cue.header.session_id, cue.cue_id);
    if (std::find(seen_cues_.begin(), seen_cues_.end(), key) != seen_cues_.end()) continue;
    seen_cues_.push_back(key);
    if (cue.condition_size > 0 && !cue.station_session.empty()) {
      // One command of this run's condition (a trial of an experiment); a condition sent
      // again by another instructor session replaces the count.
      if (from != condition_from_) {
        condition_from_ = from;
        condition_received_ = 0;
      }
      condition_size_ = cue.condition_size;
      ++condition_received_;
    }
    if (const std::string why_not = CheckCue(cue.kind, cue.param, cue.off); !why_not.empty()) {
      ++totals_.cues_rejected;
      ++totals_.cues_invalid;
      PublishEvent(net::TaskEventKind::kCueRejected, last_.step, cue.cue_id, cue.param, why_not);
      continue;
    }
    state::CueRequest request{cue.cue_id, cue.kind, cue.param, cue.header.step, cue.off};
    if (!rings_.cues.TryPush(request)) {
      ++totals_.cues_rejected;
      PublishEvent(net::TaskEventKind::kCueRejected, last_.step, cue.cue_id, cue.param,
                   "cue queue full");
    }
  }
}

void StationPublisher::Drain() {
  TickSnapshot s;
  while (rings_.snapshots.TryPop(s)) {
    ++totals_.snapshots;
    if (period_windows_.empty() || (period_windows_.back().ticks == PeriodWindow::kTicks &&
                                    period_windows_.size() < PeriodWindow::kMaxWindows)) {
      period_windows_.push_back(PeriodWindow{s.stamp_ns});
      log_periods_.Reset();
    }
    PeriodWindow& log = period_windows_.back();
    const bool logging = log.ticks < PeriodWindow::kTicks;
    if (logging) ++log.ticks;
    if (have_last_) {  // the first period of a run has no predecessor
      run_periods_.Add(s.period_ns);
      window_periods_.Add(s.period_ns);
      if (logging) log_periods_.Add(s.period_ns);
    }
    if (s.overrun) {
      ++totals_.overruns;
      ++window_overruns_;
      if (logging) ++log.overruns;
    }
    if (logging && log.ticks == PeriodWindow::kTicks) ClosePeriodWindow();
    ++window_ticks_;
    if (s.has_state_hash) {
      totals_.has_state_hash = true;
      totals_.state_hash_step = s.step;
      totals_.state_hash = s.state_hash;
    }
    for (int i = 0; i < s.module_count && i < static_cast<int>(window_step_time_sum_s_.size());
         ++i) {
      window_step_time_sum_s_[i] += s.modules[i].step_time_s;
      window_step_time_max_s_[i] = std::max(window_step_time_max_s_[i], s.modules[i].step_time_s);
      run_step_times_[i].Add(std::llround(s.modules[i].step_time_s * 1e9));
    }
    // DeviceInput: every step, the replay source.
    w_->input_plain.header = MakeHeader(s.step, s.stamp_ns);
    w_->input_plain.p_WT = E(s.p_WT_device);
    w_->input_plain.q_WT = Q(s.q_WT_device);
    w_->input_plain.gripper = s.gripper;
    w_->input_plain.buttons = s.buttons;
    w_->input_plain.state_hash = s.step_hash;
    if (s.has_second_tool) {
      w_->input_plain.p_WT2 = E(s.second.p_WT_device);
      w_->input_plain.q_WT2 = Q(s.second.q_WT_device);
      w_->input_plain.gripper2 = s.second.gripper;
      w_->input_plain.buttons2 = s.second.buttons;
    }
    net::ToMsg(w_->input_plain, w_->input_msg);
    if (w_->input->write(&w_->input_msg)) {
      ++totals_.input_published;
    } else {
      ++totals_.input_write_failed;
    }
    for (int i = 0; i < s.ack_count; ++i) {
      const state::CueAck& a = s.acks[i];
      totals_.cues_applied.push_back({a, s.step});
      PublishEvent(net::TaskEventKind::kCueApplied, s.step, a.cue_id, a.param,
                   std::string(cues::CueKindName(a.kind)) + (a.off ? " off" : ""));
    }
    // Value: the needle's clearance, else the faulting module's strain or force.
    const double event_value = s.has_needle ? s.needle.clearance_m : s.fault_value;
    if (s.contact_event > 0) {
      PublishEvent(net::TaskEventKind::kContactBegin, s.step, 0, event_value, "");
    } else if (s.contact_event < 0) {
      PublishEvent(net::TaskEventKind::kContactEnd, s.step, 0, event_value, "");
    }
    // Device faults: one event when a fault begins (or changes), one when it ends.
    if (s.device_fault != last_device_fault_) {
      if (s.device_fault != 0) {
        PublishEvent(net::TaskEventKind::kDeviceFault, s.step, 0, s.device_fault,
                     std::string("device: ") +
                         DeviceFaultName(static_cast<DeviceFault>(s.device_fault)) +
                         "; tool held, force ramped to zero");
      } else {
        PublishEvent(net::TaskEventKind::kDeviceOk, s.step, 0, 0, "device: valid samples again");
      }
      last_device_fault_ = s.device_fault;
    }
    if (config_.on_snapshot) config_.on_snapshot(s);
    last_ = s;
    have_last_ = true;
  }
}

// The visual cues of the latest step as drawing data (common/cues/cue_overlay.h), published
// with the tool at the mirror rate (empty when no visual cue is on: the views clear).
void StationPublisher::PublishOverlay() {
  const TickSnapshot& s = last_;
  cues::OverlayInput in;
  in.step = s.step;
  in.active = s.active_cues;
  in.param = s.cue.param;
  in.path = loop_.simulation().path();
  in.tolerance_m = scene_.task.tolerance_m;
  in.p_WT = E(s.p_WT);
  in.p_W_nearest = E(s.cue.p_W_nearest);
  in.deviation_m = s.cue.deviation_m;
  in.clearance_m = s.cue.clearance_m;
  in.has_wall_points = s.cue.has_wall_points != 0;
  in.p_W_tool_near = E(s.cue.p_W_tool_near);
  in.p_W_wall = E(s.cue.p_W_wall);
  in.prediction_valid = s.cue.prediction_valid != 0;
  in.warning = s.cue.warning != 0;
  in.p_W_end = E(s.cue.p_W_end);
  in.prediction_error_m = s.cue.prediction_error_m;
  cues::CalcCueOverlay(in, w_->overlay_plain);
  net::ToMsg(MakeHeader(s.step, s.stamp_ns), net::ActiveCuesToWire(s.active_cues),
             w_->overlay_plain, w_->overlay_msg);
  w_->overlay->write(&w_->overlay_msg);
}

void StationPublisher::PublishMirror() {
  if (!have_last_) return;
  const TickSnapshot& s = last_;
  w_->tool_plain.header = MakeHeader(s.step, s.stamp_ns);
  w_->tool_plain.p_WT = E(s.p_WT);
  w_->tool_plain.q_WT = Q(s.q_WT);
  w_->tool_plain.f_T_W = E(s.f_T_W);
  w_->tool_plain.tremor_rms_m = s.has_tremor ? s.tremor_rms_m : 0.0;
  w_->tool_plain.active_cues = s.active_cues;
  w_->tool_plain.has_second_tool = s.has_second_tool != 0;
  if (s.has_second_tool != 0) {
    w_->tool_plain.p_WT2 = E(s.second.p_WT_device);
    w_->tool_plain.q_WT2 = Q(s.second.q_WT_device);
    w_->tool_plain.f_T2_W = E(s.second.f_T_W);
  }
  static_assert(net::kMaxStitches == state::kMaxStitches);
  w_->tool_plain.stitch_count = s.stitch_count;
  w_->tool_plain.stitch_azimuth_rad = s.stitch_azimuth_rad;
  w_->tool_plain.stitch_bite_m = s.stitch_bite_m;
  net::ToMsg(w_->tool_plain, w_->tool_msg);
  w_->tool->write(&w_->tool_msg);
  PublishOverlay();
  if (w_->needle != nullptr && s.has_needle) {
    auto& n = w_->needle_plain;
    n.header = MakeHeader(s.step, s.stamp_ns);
    n.p_WN = E(s.needle.p_WN);
    n.q_WN = Q(s.needle.q_WN);
    n.clearance_m = s.needle.clearance_m;
    n.contact = s.needle.contact != 0;
    n.s_rad = s.needle.s_rad;
    n.p_WD = E(s.needle.p_WD);
    n.p_WB = E(s.needle.p_WB);
    n.status = ToNet(s.needle.status);
    net::ToMsg(n, w_->needle_msg);
    w_->needle->write(&w_->needle_msg);
  }
  if (view_frames_ != nullptr) EncodeViewFrame();
}

// The view frame of this mirror period: the states just published, the thread and tissue
// frames last taken, the latest score and telemetry.
void StationPublisher::EncodeViewFrame() {
  view::FrameSource src;
  src.tool = &w_->tool_plain;
  if (w_->needle != nullptr && last_.has_needle) src.needle = &w_->needle_plain;
  if (w_->thread != nullptr && !w_->thread_plain.nodes.empty()) src.thread = &w_->thread_plain;
  if (w_->tissue != nullptr && !w_->tissue_plain.displacement_m.empty()) {
    src.tissue = &w_->tissue_plain;
  }
  if (have_score_) src.score = &last_score_;
  if (have_telemetry_) src.telemetry = &last_telemetry_;
  src.overlay = &w_->overlay_plain;
  src.sent_realtime_ns = SystemClock().RealtimeNs();
  view::EncodeFrame(src, view_frames_->back());
  view_frames_->Publish();
}

// The modules write their large frames once per mirror period (HapticLoop); each is
// published as soon as it is taken, so its age is that of its tick, not of the mirror clock.
void StationPublisher::PublishFrames() {
  if (w_->thread != nullptr && rings_.frames.thread.Update()) {
    const ThreadFrame& f = rings_.frames.thread.front();
    auto& t = w_->thread_plain;
    t.header = MakeHeader(f.step, f.stamp_ns);
    t.nodes.resize(static_cast<std::size_t>(f.num_nodes));
    for (int i = 0; i < f.num_nodes; ++i) t.nodes[i] = E(f.p_W[i]);
    t.max_strain = f.max_strain;
    t.grasped_node = f.grasped_node;
    t.f_T_W = E(f.f_T_W);
    t.knot = knot_;
    net::ToMsg(t, w_->thread_msg);
    w_->thread->write(&w_->thread_msg);
  }
  if (w_->tissue != nullptr && rings_.frames.tissue.Update()) {
    const TissueFrame& f = rings_.frames.tissue.front();
    auto& t = w_->tissue_plain;
    t.header = MakeHeader(f.step, f.stamp_ns);
    t.nodes_x = f.nodes_x;
    t.nodes_y = f.nodes_y;
    t.mesh_revision = f.mesh_revision;
    t.unknowns = f.unknowns;
    t.max_displacement_m = f.max_displacement_m;
    t.status = ToNet(f.status);
    t.displacement_m.assign(f.w_m.begin(), f.w_m.begin() + std::size_t{f.nodes_x} * f.nodes_y);
    net::ToMsg(t, w_->tissue_msg);
    w_->tissue->write(&w_->tissue_msg);
  }
}

void StationPublisher::RecognizeKnot() {
  const auto& nodes = w_->thread_plain.nodes;
  if (nodes.size() < 2) return;
  try {
    knot_ = std::string(knot::KnotName(knot::RecognizeKnot(nodes)));
  } catch (const std::exception&) {
    knot_ = "unknown";  // degenerate polyline (e.g. coincident nodes)
  }
}

void StationPublisher::PublishTelemetry(std::int64_t now_ns) {
  net::Telemetry t;
  t.header = MakeHeader(last_.step, SystemClock().RealtimeNs());
  t.window_s = static_cast<double>(now_ns - telemetry_window_start_ns_) * 1e-9;
  t.ticks = window_ticks_;
  t.period_mean_s = window_periods_.mean_s();
  t.period_p99_s = window_periods_.Quantile_s(0.99);
  t.period_max_s = window_periods_.max_s();
  t.overruns = window_overruns_;
  t.ring_dropped = loop_.ring_dropped();
  t.realtime = config_.realtime;
  t.has_state_hash = totals_.has_state_hash;
  t.state_hash_step = totals_.state_hash_step;
  t.state_hash = totals_.state_hash;
  t.cues_invalid = totals_.cues_invalid;
  if (config_.device_samples_invalid) t.device_samples_invalid = config_.device_samples_invalid();
  for (std::size_t i = 0; i < scene_.modules.size(); ++i) {
    net::ModuleTelemetry m;
    m.name = scene_.modules[i];
    m.step_time_mean_s =
        window_ticks_ ? window_step_time_sum_s_[i] / static_cast<double>(window_ticks_) : 0.0;
    m.step_time_max_s = window_step_time_max_s_[i];
    m.error_estimate = last_.modules[i].error_estimate;
    m.warnings = last_.modules[i].warnings;
    m.error_kind = loop_.module_error_kind(i);
    t.modules.push_back(m);
  }
  net::ToMsg(t, w_->telemetry_msg);
  w_->telemetry->write(&w_->telemetry_msg);
  if (view_frames_ != nullptr) {
    last_telemetry_ = t;
    have_telemetry_ = true;
  }
  window_periods_.Reset();
  window_overruns_ = 0;
  window_ticks_ = 0;
  std::fill(window_step_time_sum_s_.begin(), window_step_time_sum_s_.end(), 0.0);
  std::fill(window_step_time_max_s_.begin(), window_step_time_max_s_.end(), 0.0);
  telemetry_window_start_ns_ = now_ns;
}

void StationPublisher::PublishScore(bool is_final) {
  state::ScoreState totals = last_.score;
  // Knot tying: the knot in the latest thread frame, once the throws are pulled (at the task's
  // end the frame is the last one published).
  if (scene_.knot_tying && w_->thread != nullptr && !w_->thread_plain.nodes.empty() &&
      totals.throws_pulled >= scene_.knot_tying->throws) {
    totals.tied_knot = static_cast<std::int32_t>(RecogniseTiedKnot(scene_, w_->thread_plain.nodes));
  }
  net::Score s = CalcScore(scene_, totals);
  s.header = MakeHeader(last_.step, SystemClock().RealtimeNs());
  s.is_final = is_final;
  net::ToMsg(s, w_->score_msg);
  w_->score->write(&w_->score_msg);
  if (view_frames_ != nullptr) {
    last_score_ = s;
    have_score_ = true;
  }
  if (is_final) final_score_ = s;
}

void StationPublisher::Run() {
  const std::int64_t period_ns =
      static_cast<std::int64_t>(std::llround(1e9 / scene_.haptic.rate_hz));
  const auto mirror_ns = static_cast<std::int64_t>(1e9 / config_.mirror_rate_hz);
  const auto telemetry_ns = static_cast<std::int64_t>(1e9 / config_.telemetry_rate_hz);
  const auto score_ns = static_cast<std::int64_t>(1e9 * config_.score_period_s);
  const auto knot_ns = static_cast<std::int64_t>(1e9 / config_.knot_rate_hz);
  std::int64_t next_knot_ns = 0;
  std::int64_t now = SystemClock().NowNs();
  next_mirror_ns_ = now;
  next_telemetry_ns_ = now + telemetry_ns;
  next_score_ns_ = now + score_ns;
  telemetry_window_start_ns_ = now;
  // The run's first event, once the readers have matched (--wait-for-recorder): written in the
  // constructor, before any reader matched, it was not delivered (volatile).
  PublishEvent(net::TaskEventKind::kTaskStart, 0, 0, 0, scene_.name);
  dds::ConditionSeq active;
  while (!stop_.load()) {
    // Wake just after the next tick is due (its snapshot is then in the ring).
    std::int64_t wake = now + period_ns;
    if (have_last_) wake = last_.tick_start_ns + period_ns + config_.wake_offset_ns;
    const std::int64_t timeout_ns = std::clamp<std::int64_t>(wake - now, 20'000, 2 * period_ns);
    w_->waitset.wait(active,
                     eprosima::fastrtps::Duration_t(0, static_cast<std::uint32_t>(timeout_ns)));
    HandleCues();
    Drain();
    PublishFrames();
    now = SystemClock().NowNs();
    if (now >= next_mirror_ns_) {
      PublishMirror();
      next_mirror_ns_ = std::max(next_mirror_ns_ + mirror_ns, now);
    }
    if (now >= next_telemetry_ns_) {
      PublishTelemetry(now);
      next_telemetry_ns_ = std::max(next_telemetry_ns_ + telemetry_ns, now);
    }
    if (now >= next_score_ns_) {
      PublishScore(false);
      next_score_ns_ = std::max(next_score_ns_ + score_ns, now);
    }
    if (w_->thread != nullptr && now >= next_knot_ns) {
      RecognizeKnot();  // on the latest published nodes; ~0.1 ms for 65 nodes
      next_knot_ns = now + knot_ns;
    }
  }
  Goodbye();
}

void StationPublisher::ClosePeriodWindow() {
  PeriodWindow& log = period_windows_.back();
  log.p99_s = log_periods_.Quantile_s(0.99);
  log.max_s = log_periods_.max_s();
}

void StationPublisher::Goodbye() {
  Drain();
  if (!period_windows_.empty() && period_windows_.back().ticks < PeriodWindow::kTicks) {
    ClosePeriodWindow();  // the partial last window
  }
  PublishMirror();
  PublishFrames();
  PublishScore(true);
  PublishEvent(net::TaskEventKind::kTaskEnd, last_.step, 0, final_score_.score, "");
  // Wait for the final samples of every writer to be acknowledged by the readers that
  // matched (the reliable ones: a best-effort reader acknowledges nothing and is not waited
  // for), within one deadline for all: 150 ms, or input_ack_wait_s for a recorded station
  // (--wait-for-recorder) so that the recorder has every step, state, event and the final
  // score even on a loaded machine. The station's own StationInfo first: a reader that matched
  // after it was written gets it as historical data, repaired on request, and a short run
  // (unpaced, a fraction of a second) can end before that; its departure below would then be
  // all that reader hears of it, and a recorder or a scores database could not name the run.
  // Then the final score and the task end. A dead reader costs the deadline once (until its
  // participant's lease drops it), not once per writer.
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(std::max(config_.input_ack_wait_s, 0.15));
  for (dds::DataWriter* w : {w_->info, w_->score, w_->events, w_->input, w_->tool, w_->overlay,
                             w_->needle, w_->thread, w_->tissue, w_->telemetry}) {
    if (w == nullptr) continue;
    const auto left_ns =
        std::max<std::int64_t>(0, std::chrono::duration_cast<std::chrono::nanoseconds>(
                                      deadline - std::chrono::steady_clock::now())
                                      .count());
    w->wait_for_acknowledgments(
        eprosima::fastrtps::Duration_t(static_cast<std::int32_t>(left_ns / 1'000'000'000),
                                       static_cast<std::uint32_t>(left_ns % 1'000'000'000)));
  }
  // Departure: dispose the station's instance, then unregister it.
  w_->info->dispose(&w_->info_msg, w_->info_handle);
  w_->info->unregister_instance(&w_->info_msg, w_->info_handle);
  w_->info->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 150'000'000));
}

}  // namespace microdex::station
