#include "station/haptic_loop.h"

#include <cmath>

#include "common/base/check.h"

namespace microdex::station {

const char* CheckCue(net::CueKind kind, double param) {
  switch (kind) {
    case net::CueKind::kClear:
      return "";
    case net::CueKind::kConvergentField:
    case net::CueKind::kDivergentField:
      if (!(param > 0 && param <= kMaxFieldStiffness_N_per_m)) {
        return "stiffness: expected 0 < k <= 2000 N/m";
      }
      return "";
    case net::CueKind::kAmplifiedTremor:
      if (!(param >= 1 && param <= kMaxTremorGain)) return "gain: expected 1 <= gain <= 20";
      return "";
  }
  return "unknown cue kind";
}

HapticLoop::HapticLoop(const scene::SceneModel& scene, Device& device,
                       std::vector<std::unique_ptr<Module>> modules, StationRings& rings,
                       rt::Clock& clock, int frame_period_steps)
    : scene_(scene),
      device_(device),
      modules_(std::move(modules)),
      rings_(rings),
      clock_(clock),
      dt_s_(1.0 / scene.haptic.rate_hz),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / scene.haptic.rate_hz))),
      frame_period_steps_(frame_period_steps) {
  MICRODEX_CHECK(modules_.size() <= static_cast<std::size_t>(kMaxStationModules));
  MICRODEX_CHECK(frame_period_steps_ >= 1);
  path_.is_segment = scene.task.path == scene::PathKind::kLine;
  path_.circle.X_WC = scene.vessel.X_WV;
  path_.circle.radius_m = scene.needle.radius_m;
  path_.segment.a_W = scene.task.line_start_m;
  path_.segment.b_W = scene.task.line_end_m;
  cues::TremorFilterDef tf;
  tf.sample_rate_hz = scene.haptic.rate_hz;
  tremor_filter_ = cues::MakeTremorFilter(tf);
  snap_.score.min_clearance_m = std::numeric_limits<double>::infinity();
}

void HapticLoop::ApplyCue(const CueRequest& cue) {
  switch (cue.kind) {
    case net::CueKind::kClear:
      field_stiffness_N_per_m_ = 0;
      tremor_gain_ = 1;
      break;
    case net::CueKind::kConvergentField:
      field_stiffness_N_per_m_ = cue.param;
      break;
    case net::CueKind::kDivergentField:
      field_stiffness_N_per_m_ = -cue.param;
      break;
    case net::CueKind::kAmplifiedTremor:
      tremor_gain_ = cue.param;
      break;
  }
  if (snap_.ack_count < kMaxAcksPerTick) {
    snap_.acks[snap_.ack_count++] = {cue.cue_id, cue.kind, cue.param};
  }
}

void HapticLoop::TakeDueCues() {
  CueRequest cue;
  while (pending_count_ < kMaxPendingCues && rings_.cues.TryPop(cue)) {
    pending_[pending_count_++] = cue;
  }
  // Apply in arrival order those due now; at most kMaxAcksPerTick per step, the rest wait
  // for the next step (and are acknowledged with it).
  int kept = 0;
  for (int i = 0; i < pending_count_; ++i) {
    if (pending_[i].apply_at_step <= step_ && snap_.ack_count < kMaxAcksPerTick) {
      ApplyCue(pending_[i]);
    } else {
      pending_[kept++] = pending_[i];
    }
  }
  pending_count_ = kept;
}

void HapticLoop::UpdateScore(const Eigen::Vector3d& p_device, TickSnapshot& s) {
  ScoreTotals& t = s.score;
  t.time_s += dt_s_;
  const Eigen::Vector3d p_ideal =
      scene_.CalcIdealToolPose(static_cast<double>(step_) * dt_s_).translation();
  if (have_prev_) {
    t.path_length_m += (p_device - p_device_prev_).norm();
    t.ideal_path_length_m += (p_ideal - p_ideal_prev_).norm();
  }
  p_device_prev_ = p_device;
  p_ideal_prev_ = p_ideal;
  have_prev_ = true;
  s.contact_event = 0;
  if (s.has_needle && s.needle.status == 0) {
    const double c = s.needle.clearance_m;
    t.clearance_sum_m += c;
    ++t.clearance_samples;
    t.min_clearance_m = std::min(t.min_clearance_m, c);
  }
  if (s.fault) {
    t.time_in_contact_s += dt_s_;
    steps_free_ = 0;
    if (!in_episode_) {
      in_episode_ = true;
      ++t.contacts;
      s.contact_event = 1;
    }
  } else if (in_episode_ && ++steps_free_ >= kContactReleaseSteps) {
    in_episode_ = false;
    s.contact_event = -1;
  }
  if (s.has_tremor) {
    t.tremor_sq_sum_m2 += s.tremor_band_m * s.tremor_band_m;
    ++t.tremor_samples;
  }
}

void HapticLoop::Tick(std::int64_t tick_start_ns, std::int64_t period_ns, std::int64_t stamp_ns,
                      bool overrun) {
  TickSnapshot& s = snap_;  // totals carry over from the previous step
  s.ack_count = 0;
  s.step = step_;
  s.tick_start_ns = tick_start_ns;
  s.stamp_ns = stamp_ns;
  s.period_ns = period_ns;
  s.overrun = overrun ? 1 : 0;

  // 1. Device.
  const DeviceSample d = device_.Read(step_);
  const Eigen::Vector3d p_device = d.X_WT.translation();

  // 2. Cues: those due at this step, then their effect on the tool and the force.
  TakeDueCues();
  ToolInput in;
  in.step = step_;
  in.dt_s = dt_s_;
  in.X_WT = d.X_WT;
  in.p_WT_device = p_device;
  // The band filter runs every step so that switching amplification on is seamless.
  const Eigen::Vector3d band = cues::StepTremorFilter(tremor_filter_, p_device, tremor_state_);
  if (tremor_gain_ != 1) in.X_WT.translation() = p_device + (tremor_gain_ - 1) * band;
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  if (field_stiffness_N_per_m_ != 0) {
    f += cues::CalcPathFieldForce(path_, in.X_WT.translation(), field_stiffness_N_per_m_,
                                  scene_.haptic.max_force_N);
  }

  // 3. Modules; every frame period also their large frames (timed with the step).
  const bool frame_step = step_ % static_cast<std::uint64_t>(frame_period_steps_) == 0;
  s.module_count = static_cast<int>(modules_.size());
  s.fault = 0;
  s.fault_value = 0;
  for (std::size_t i = 0; i < modules_.size(); ++i) {
    Module& m = *modules_[i];
    const std::int64_t t0 = clock_.NowNs();
    m.Step(in, f);
    if (frame_step) m.WriteFrame(step_, stamp_ns, rings_.frames);
    const std::int64_t t1 = clock_.NowNs();
    s.modules[i] = {static_cast<double>(t1 - t0) * 1e-9, m.error_estimate(), m.warnings()};
    if (!s.fault && m.fault()) {
      s.fault = 1;
      s.fault_value = m.fault_value();
    }
  }

  // 4. Force out: finite and saturated, always.
  if (!f.allFinite()) {
    f.setZero();
    ++force_warnings_;
  }
  const double fn = f.norm();
  if (fn > scene_.haptic.max_force_N) f *= scene_.haptic.max_force_N / fn;
  device_.WriteForce(f);

  // 5. Snapshot and score.
  const Eigen::Quaterniond q_dev(d.X_WT.rotation());
  const Eigen::Quaterniond q_tool(in.X_WT.rotation());
  const Eigen::Vector3d p_tool = in.X_WT.translation();
  s.p_WT_device = {p_device.x(), p_device.y(), p_device.z()};
  s.q_WT_device = {q_dev.w(), q_dev.x(), q_dev.y(), q_dev.z()};
  s.gripper = d.gripper;
  s.buttons = d.buttons;
  s.p_WT = {p_tool.x(), p_tool.y(), p_tool.z()};
  s.q_WT = {q_tool.w(), q_tool.x(), q_tool.y(), q_tool.z()};
  s.f_T_W = {f.x(), f.y(), f.z()};
  s.active_cues = 0;
  if (field_stiffness_N_per_m_ > 0) s.active_cues |= 1u << unsigned(net::CueKind::kConvergentField);
  if (field_stiffness_N_per_m_ < 0) s.active_cues |= 1u << unsigned(net::CueKind::kDivergentField);
  if (tremor_gain_ != 1) s.active_cues |= 1u << unsigned(net::CueKind::kAmplifiedTremor);
  for (const auto& m : modules_) m->WriteSnapshot(s);
  s.force_warnings = force_warnings_;
  UpdateScore(p_device, s);
  if (!rings_.snapshots.TryPush(s)) ring_dropped_.fetch_add(1, std::memory_order_relaxed);
  ++step_;
}

void HapticLoop::Run(const std::atomic<bool>& stop, std::uint64_t max_steps) {
  std::int64_t deadline = clock_.NowNs();
  std::int64_t prev_start = -1;
  while (!stop.load(std::memory_order_relaxed) && step_ < max_steps) {
    deadline += period_ns_;
    clock_.SleepUntilNs(deadline);
    const std::int64_t start = clock_.NowNs();
    const std::int64_t late = start - deadline;
    const bool overrun = late > period_ns_;
    if (overrun) ++overruns_;
    Tick(start, prev_start < 0 ? period_ns_ : start - prev_start, clock_.RealtimeNs(), overrun);
    prev_start = start;
    if (late > kResyncPeriods * period_ns_) deadline = start;
  }
}

}  // namespace microdex::station
