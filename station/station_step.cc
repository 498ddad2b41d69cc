#include "station/station_step.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/base/check.h"
#include "station/placement_module.h"

namespace microdex::station {

Simulation::Simulation(const scene::SceneModel& scene)
    : scene_(scene), dt_s_(1.0 / scene.haptic.rate_hz), modules_(MakeModules(scene)) {
  MICRODEX_CHECK(modules_.size() <= static_cast<std::size_t>(kMaxStationModules));
  // The guidance fields pull towards the task's path (a hold: its target point).
  path_.is_segment =
      scene.task.path == scene::PathKind::kLine || scene.task.kind == scene::TaskKind::kTremorHold;
  path_.circle.X_WC = scene.vessel.X_WV;
  path_.circle.radius_m = scene.needle.radius_m;
  if (scene.task.path == scene::PathKind::kCircle) {
    path_.circle.X_WC =
        Eigen::Translation3d(scene.task.circle_center_m) * Eigen::Isometry3d::Identity();
    path_.circle.radius_m = scene.task.circle_radius_m;
  }
  path_.segment.a_W = scene.task.line_start_m;
  path_.segment.b_W = scene.task.line_end_m;
  if (scene.task.kind == scene::TaskKind::kTremorHold) {
    path_.segment.a_W = path_.segment.b_W = scene.task.target_m;
  }
  cues::TremorFilterDef tf;
  tf.sample_rate_hz = scene.haptic.rate_hz;
  tremor_filter_ = cues::MakeTremorFilter(tf);
  cues::EndPointPredictorDef pd;
  pd.sample_rate_hz = scene.haptic.rate_hz;
  predictor_ = cues::MakeEndPointPredictor(pd);
  step_time_s_.assign(modules_.size(), 0.0);
}

state::StationState Simulation::MakeInitialState(std::uint64_t seed) const {
  state::StationState s;
  state::SeedStationState(seed, s);
  s.score.min_clearance_m = std::numeric_limits<double>::infinity();
  if (scene_.second_hand) {
    s.second_tool.emplace();
    s.second_tool->X_WT_device = s.second_tool->X_WT = scene_.CalcIdealSecondToolPose(0);
  }
  for (const auto& m : modules_) m->InitState(s);
  // (Every kind's default parameter and the wall on: CueState's defaults.)
  s.cues.clearance_m = std::numeric_limits<double>::infinity();
  // The scene's cues on from the first step (cue id 0: the scene's own).
  for (const auto& [kind, param] : scene_.cues.on) {
    if (s.cues.pending_count < state::kMaxPendingCues && cues::IsCueValid(kind, param)) {
      s.cues.pending[s.cues.pending_count++] = {0, kind, param, 0, false};
    }
  }
  return s;
}

namespace {

// Applies one cue to the cue state and acknowledges it with this step. Clear switches every
// kind off but the wall (a property of the scene the instructor turns down with `wall:0`).
void ApplyCue(const state::CueRequest& cue, state::CueState& c) {
  if (cue.kind == cues::CueKind::kClear) {
    c.active &= cues::CueBit(cues::CueKind::kWall);
  } else if (cue.off) {
    c.active &= ~cues::CueBit(cue.kind);
  } else {
    c.active |= cues::CueBit(cue.kind);
    c.param[static_cast<std::size_t>(cue.kind)] = cue.param;
    // One field at a time: the convergent and the divergent field exclude each other.
    if (cue.kind == cues::CueKind::kConvergentField) {
      c.active &= ~cues::CueBit(cues::CueKind::kDivergentField);
    } else if (cue.kind == cues::CueKind::kDivergentField) {
      c.active &= ~cues::CueBit(cues::CueKind::kConvergentField);
    }
  }
  c.acks[c.ack_count++] = {cue.cue_id, cue.kind, cue.param, cue.off};
}

// Reads the input's cue requests and state.cues; writes state.cues (pending, in force, acks).
// In arrival order, those due at this step are applied, at most kMaxAcksPerStep per step (the
// rest wait for the next step and are acknowledged with it); requests beyond the pending
// capacity are dropped (the caller hands over no more than there is room for).
void TakeCues(std::span<const state::CueRequest> arrived, std::uint64_t step, state::CueState& c) {
  c.ack_count = 0;
  for (const state::CueRequest& r : arrived) {
    if (c.pending_count < state::kMaxPendingCues) c.pending[c.pending_count++] = r;
  }
  int kept = 0;
  for (int i = 0; i < c.pending_count; ++i) {
    if (c.pending[i].apply_at_step <= step && c.ack_count < state::kMaxAcksPerStep) {
      // Checked where it entered (publisher, command line, scene); checked again here so that
      // no path can put an out-of-limits parameter into the state.
      if (cues::IsCueValid(c.pending[i].kind, c.pending[i].param, c.pending[i].off)) {
        ApplyCue(c.pending[i], c);
      }
    } else {
      c.pending[kept++] = c.pending[i];
    }
  }
  c.pending_count = kept;
}

// Reads the device sample and state.cues; writes state.tool's device fields, the tremor band
// (filtered every step so that switching amplification on is seamless) and the tool pose.
void CalcToolAfterCues(const cues::TremorFilterModel& filter, const DeviceSample& d,
                       state::StationState& s) {
  s.tool.X_WT_device = d.X_WT;
  s.tool.gripper = d.gripper;
  s.tool.buttons = d.buttons;
  s.tool.device_fault = static_cast<std::uint8_t>(d.fault);
  const Eigen::Vector3d p_device = d.X_WT.translation();
  s.cues.tremor_band_m = cues::StepTremorFilter(filter, p_device, s.cues.tremor_filter);
  s.tool.X_WT = d.X_WT;
  if (s.cues.on(cues::CueKind::kAmplifiedTremor)) {
    const double gain = s.cues.p(cues::CueKind::kAmplifiedTremor);
    s.tool.X_WT.translation() = p_device + (gain - 1) * s.cues.tremor_band_m;
  }
}

// Bimanual scenes: the second device's sample is the second tool (the cues act on the first).
void SetSecondTool(const DeviceSample& d, state::ToolState& t) {
  t.X_WT_device = d.X_WT;
  t.gripper = d.gripper;
  t.buttons = d.buttons;
  t.device_fault = static_cast<std::uint8_t>(d.fault);
  t.X_WT = d.X_WT;
}

// Reads state.cues, the tool (and the loop module's nearest wire point); returns the field's
// force on the tool: convergent (a spring to the path) or divergent (across the path only).
Eigen::Vector3d CalcCueForce(const cues::IdealPath& path, double max_force_N,
                             const state::StationState& s) {
  const bool conv = s.cues.on(cues::CueKind::kConvergentField);
  const bool div = s.cues.on(cues::CueKind::kDivergentField);
  if (!conv && !div) return Eigen::Vector3d::Zero();
  const double k =
      conv ? s.cues.p(cues::CueKind::kConvergentField) : s.cues.p(cues::CueKind::kDivergentField);
  const Eigen::Vector3d p_WT = s.tool.X_WT.translation();
  if (s.loop) {  // the wire course: towards the wire-axis point the loop module last found
    return cues::CalcPointFieldForce(p_WT, s.loop->p_WA_centre, conv ? k : -k, max_force_N);
  }
  if (div) return cues::CalcDivergentFieldForce(path, p_WT, k, max_force_N);
  return cues::CalcPathFieldForce(path, p_WT, k, max_force_N);
}

// The cue's force, limited (common/cues/force_limits.h): finite, saturated and rate-limited,
// so that no cue parameter can make the device unstable (state.cues.f_cue_W). The modules'
// contact forces are not rate-limited: a stiff contact rendered through a rate limit lags
// behind the motion and makes the hand–tool loop ring (the thread's grasp force, for one).
Eigen::Vector3d LimitCueForce(const Eigen::Vector3d& f_cue, double max_force_N, double dt_s,
                              state::StationState& s) {
  const cues::ForceLimitResult r =
      cues::LimitForce(f_cue, s.cues.f_cue_W, max_force_N, cues::kMaxForceRate_N_per_s, dt_s);
  if (r.rate_limited) ++s.cues.force_rate_limited;
  s.cues.f_cue_W = r.f_N;
  return r.f_N;
}

// Reads a tool; writes its f_T_W and tau_T_W: finite and saturated, always; during a device
// fault both ramp to zero at the limiter's rate (the torque in the same time as the force:
// its rate scaled by max_torque / max_force).
void LimitToolWrench(const Eigen::Vector3d& f, const Eigen::Vector3d& tau,
                     const scene::HapticDef& haptic, double dt_s, state::ToolState& tool) {
  const bool fault = tool.device_fault != 0;
  const double inf = std::numeric_limits<double>::infinity();
  const double rate = fault ? cues::kMaxForceRate_N_per_s : inf;
  const cues::ForceLimitResult rf = cues::LimitForce(fault ? Eigen::Vector3d::Zero() : f,
                                                     tool.f_T_W, haptic.max_force_N, rate, dt_s);
  const double torque_rate =
      fault ? cues::kMaxForceRate_N_per_s * haptic.max_torque_Nm / haptic.max_force_N : inf;
  const cues::ForceLimitResult rt = cues::LimitForce(
      fault ? Eigen::Vector3d::Zero() : tau, tool.tau_T_W, haptic.max_torque_Nm, torque_rate, dt_s);
  if (rf.non_finite || rt.non_finite) ++tool.force_warnings;
  tool.f_T_W = rf.f_N;
  tool.tau_T_W = rt.f_N;
}

// Reads the tool, the needle and tremor sections and this step's fault; writes state.score.
void UpdateScore(const scene::SceneModel& scene, double dt_s, state::StationState& s) {
  state::ScoreState& t = s.score;
  t.time_s += dt_s;
  const Eigen::Vector3d p_device = s.tool.X_WT_device.translation();
  const Eigen::Vector3d p_ideal =
      scene.CalcIdealToolPose(static_cast<double>(s.step) * dt_s).translation();
  Eigen::Map<Eigen::Vector3d> p_device_prev(t.p_WT_device_prev.data());
  Eigen::Map<Eigen::Vector3d> p_ideal_prev(t.p_WT_ideal_prev.data());
  if (t.have_prev) {
    t.path_length_m += (p_device - p_device_prev).norm();
    t.ideal_path_length_m += (p_ideal - p_ideal_prev).norm();
  }
  p_device_prev = p_device;
  p_ideal_prev = p_ideal;
  t.have_prev = 1;
  t.contact_event = 0;
  if (s.needle && s.needle->clearance.status == geometry::ClearanceStatus::kOk) {
    const double c = s.needle->clearance.clearance_m;
    t.clearance_sum_m += c;
    ++t.clearance_samples;
    t.min_clearance_m = std::min(t.min_clearance_m, c);
  }
  if (t.fault) {
    t.time_in_contact_s += dt_s;
    t.steps_free = 0;
    if (!t.in_episode) {
      t.in_episode = 1;
      ++t.contacts;
      t.contact_event = 1;
    }
  } else if (t.in_episode && ++t.steps_free >= state::kContactReleaseSteps) {
    t.in_episode = 0;
    t.contact_event = -1;
  }
  if (s.tremor) {
    t.tremor_sq_sum_m2 += s.tremor->band_m * s.tremor->band_m;
    ++t.tremor_samples;
  }
}

// The device's distance from what the task asks: the hold target, or the ideal path.
double CalcDeviation(const scene::SceneModel& scene, const cues::IdealPath& path,
                     const Eigen::Vector3d& p_W) {
  if (scene.task.kind == scene::TaskKind::kTremorHold ||
      scene.task.kind == scene::TaskKind::kKnotTying) {
    return (p_W - scene.task.target_m).norm();
  }
  if (path.is_segment) return (p_W - cues::CalcNearestOnSegment(path.segment, p_W)).norm();
  Eigen::Vector3d q_W;
  if (!cues::CalcNearestOnCircle(path.circle, p_W, &q_W)) return path.circle.radius_m;
  return (p_W - q_W).norm();
}

// Where the device is along the path, 0 at the start and 1 at the end (unclamped).
double CalcPathProgress(const scene::SceneModel& scene, const Eigen::Vector3d& p_W) {
  const scene::TaskDef& t = scene.task;
  if (t.path == scene::PathKind::kLine) {
    const Eigen::Vector3d ab = t.line_end_m - t.line_start_m;
    return (p_W - t.line_start_m).dot(ab) / ab.squaredNorm();
  }
  const Eigen::Vector3d p_V = t.path == scene::PathKind::kCircle
                                  ? Eigen::Vector3d(p_W - t.circle_center_m)
                                  : Eigen::Vector3d(scene.vessel.X_WV.inverse() * p_W);
  // The azimuth unwrapped to the turn centred on the path: the part of the circle the path does
  // not cover is split evenly before its start and after its end.
  constexpr double kTwoPi = 2 * 3.141592653589793;
  const double lo =
      t.start_azimuth_rad - 0.5 * (kTwoPi - (t.end_azimuth_rad - t.start_azimuth_rad));
  double theta = std::fmod(std::atan2(p_V.y(), p_V.x()) - lo, kTwoPi);
  if (theta < 0) theta += kTwoPi;
  theta += lo;
  return (theta - t.start_azimuth_rad) / (t.end_azimuth_rad - t.start_azimuth_rad);
}

// Reads the device, the tremor band and state.score; writes the task's part of state.score:
// deviation, time beyond the tolerance, passes and the outcome. Frozen once the task ended.
void UpdateTask(const scene::SceneModel& scene, const cues::IdealPath& path, double dt_s,
                state::StationState& s) {
  state::ScoreState& t = s.score;
  const scene::TaskDef& task = scene.task;
  const Eigen::Vector3d p_device = s.tool.X_WT_device.translation();
  // The loop along a wire: the loop module's offset from the wire's axis (both).
  const bool on_wire = task.kind == scene::TaskKind::kLoopAlongWire;
  const double deviation = on_wire ? s.loop->offset_m : CalcDeviation(scene, path, p_device);
  t.deviation_sum_m += deviation;
  t.deviation_max_m = std::max(t.deviation_max_m, deviation);
  t.drift_sum_m +=
      on_wire ? deviation : CalcDeviation(scene, path, p_device - s.cues.tremor_band_m);
  ++t.deviation_samples;
  if (deviation > task.tolerance_m) t.time_outside_s += dt_s;
  if (task.kind == scene::TaskKind::kTremorHold) {
    t.progress = std::min(t.time_s / task.hold_s, 1.0);
    if (t.time_s >= task.hold_s - 0.5 * dt_s) t.outcome = 1;
  } else if (task.kind == scene::TaskKind::kGrasp) {
    // Lift the object to the lift height and hold it there for hold_s.
    const grasp::GraspState& g = s.grasp->grasp;
    t.object_rotation_rad = g.metrics.max_induced_rotation_rad;
    t.jaw_alignment_rad = g.metrics.alignment_angle_rad;
    t.object_drops = g.metrics.drops;
    if (g.metrics.held && g.X_WO.p_W.z() >= scene.grasp->lift_height_m) t.goal_time_s += dt_s;
    t.progress = std::min(t.goal_time_s / task.hold_s, 1.0);
    if (t.goal_time_s >= task.hold_s - 0.5 * dt_s) t.outcome = 1;
  } else if (task.kind == scene::TaskKind::kKnotPlacement) {
    const PlacementErrors e = CalcPlacementErrors(*scene.placement, *s.placement);
    t.stitches = s.placement->count;
    t.spacing_error_rad = e.spacing_rms_rad;
    t.bite_error_m = e.bite_rms_m;
    t.progress = static_cast<double>(t.stitches) / scene.placement->stitches;
    if (t.stitches >= scene.placement->stitches) t.outcome = 1;
  } else if (task.kind == scene::TaskKind::kKnotTopology) {
    const state::KnotQuizState& k = *s.knots;
    const auto items = static_cast<std::int32_t>(scene.knots->items.size());
    t.answers = k.item;
    t.wrong_answers = k.item - k.correct;
    t.response_time_sum_s = k.response_time_sum_s;
    t.progress = static_cast<double>(k.item) / items;
    if (k.item >= items) t.outcome = 1;
  } else if (task.kind == scene::TaskKind::kKnotTying) {
    // Each throw tied and pulled, then the hold; done when the hold is over.
    const state::KnotTieState& k = s.thread->tie;
    const scene::KnotTyingSceneDef& kt = *scene.knot_tying;
    t.throws_pulled = k.pulled;
    t.torn_m = k.bite_cut_m;
    t.bite_pulled_out = k.bite_pulled_out;
    // The hold: the hands keep the hold tension on both ends, through the trainee's deviations
    // (sampled once these are fully coupled in, 0.25 s into the hold).
    if (k.holding != 0 && k.done == 0 && k.coupling >= 1.0) {
      const thread::ThreadState& th = s.thread->thread;
      const double target = kt.hold_tension_N;
      for (const int slot : {k.hands.standing_slot, k.hands.driver_slot}) {
        if (slot < 0 || slot >= static_cast<int>(th.grasps.size())) continue;
        const double pull = th.grasps[static_cast<std::size_t>(slot)].f_T_W.norm();
        if (!std::isfinite(pull)) continue;
        const double e = (pull - target) / target;
        t.tension_sq_sum += e * e;
        ++t.tension_samples;
      }
    }
    t.progress = k.done != 0 ? 1.0 : static_cast<double>(k.pulled) / (kt.throws + 1);
    if (k.done != 0) t.outcome = 1;
  } else if (task.kind == scene::TaskKind::kLoopAlongWire) {
    // One pass along the course; the deviation is the offset from the wire's axis.
    const double length = scene.loop->wire.Length();
    t.progress = std::clamp(s.loop->s_m / length, 0.0, 1.0);
    if (t.progress >= 0.98) t.outcome = 1;
  } else if (task.kind != scene::TaskKind::kFollowPath) {
    // A pass ends when the device reaches the far end of the path (forward passes) or the
    // start (return passes).
    constexpr double kEndMargin = 0.02;
    const double f = CalcPathProgress(scene, p_device);
    const bool forward = t.passes_done % 2 == 0;
    t.progress = std::clamp(forward ? f : 1.0 - f, 0.0, 1.0);
    if (t.progress >= 1.0 - kEndMargin) {
      ++t.passes_done;
      t.progress = 0;
    }
    if (task.kind == scene::TaskKind::kNylonLoop) t.shape_error_m = s.thread->shape_error_m;
    if (task.kind == scene::TaskKind::kNeedleThroughTissue) {
      const puncture::PunctureState& p = s.tissue->puncture;
      const Eigen::Isometry3d& X_WS = scene.tissue->X_WS;
      if (p.have_entry != 0) {
        t.entry_error_m = (X_WS * p.p_S_entry - scene.puncture->p_W_entry_target).norm();
      }
      if (p.have_exit != 0) {
        t.exit_error_m = (X_WS * p.p_S_exit - scene.puncture->p_W_exit_target).norm();
      }
      t.peak_strain = p.peak_strain;
      t.torn_m = p.torn_m;
      t.off_circle_m = p.off_circle_m;
      t.punctures = p.punctures;
    }
    // The needle through tissue is done only once it has come out.
    const bool out =
        task.kind != scene::TaskKind::kNeedleThroughTissue || s.tissue->puncture.have_exit != 0;
    if (t.passes_done >= task.passes && out) t.outcome = 1;
  }
  if (t.outcome == 0 && t.time_s >= task.time_limit_s - 0.5 * dt_s) t.outcome = 2;
  if (t.outcome != 0) t.end_step = s.step;
}

// The nearest point of the task's path (the loop: the wire-axis point its module found).
Eigen::Vector3d CalcNearestPathPoint(const cues::IdealPath& path, const state::StationState& s,
                                     const Eigen::Vector3d& p_W) {
  if (s.loop) return s.loop->p_WA_centre;
  if (path.is_segment) return cues::CalcNearestOnSegment(path.segment, p_W);
  Eigen::Vector3d q_W = p_W;
  cues::CalcNearestOnCircle(path.circle, p_W, &q_W);
  return q_W;
}

// Reads the tool, the modules' clearances, this step's fault and contact event; writes the
// cue signals of state.cues (what the visual and audio cues show) and the end-point
// prediction. Computed whether or not the cues are on, so switching one on is seamless.
void UpdateCueSignals(const scene::SceneModel& scene, const cues::IdealPath& path,
                      const cues::EndPointPredictorModel& predictor, double dt_s,
                      state::StationState& s) {
  state::CueState& c = s.cues;
  const Eigen::Vector3d p_WT = s.tool.X_WT.translation();
  c.p_W_nearest = CalcNearestPathPoint(path, s, p_WT);
  c.deviation_m = s.loop ? s.loop->offset_m : (p_WT - c.p_W_nearest).norm();
  // The clearance to the task's walls; without walls, the margin to the task's tolerance.
  if (s.needle && s.needle->clearance.status == geometry::ClearanceStatus::kOk) {
    c.clearance_m = s.needle->clearance.clearance_m;
  } else if (s.loop && s.loop->clearance.status == geometry::LoopWireStatus::kOk) {
    c.clearance_m = s.loop->clearance.clearance_m;
  } else if (!s.needle && !s.loop) {
    c.clearance_m = scene.task.tolerance_m - c.deviation_m;
  }
  c.click = s.score.contact_event > 0 ? 1 : 0;
  c.error = s.score.fault;
  // Predictive: the device's sub-movement end point, its distance from the path.
  state::PredictorState& pr = c.prediction;
  const cues::EndPointPrediction e =
      cues::StepEndPointPredictor(predictor, s.tool.X_WT_device.translation(), pr.predictor);
  pr.valid = e.valid ? 1 : 0;
  if (e.valid) {
    pr.p_W_end = e.p_W_end;
    pr.error_m = s.loop ? (e.p_W_end - s.loop->p_WA_centre).norm()
                        : (e.p_W_end - CalcNearestPathPoint(path, s, e.p_W_end)).norm();
  }
  cues::StepPredictiveWarning(e, pr.error_m, c.p(cues::CueKind::kPredictive), dt_s, pr.predictor);
}

}  // namespace

void StepStation(Simulation& sim, const StationInput& in, state::StationState& s) {
  const scene::SceneModel& scene = sim.scene_;
  TakeCues(in.cues, s.step, s.cues);
  CalcToolAfterCues(sim.tremor_filter_, in.device, s);
  if (s.second_tool) SetSecondTool(in.second, *s.second_tool);
  Eigen::Vector3d f = LimitCueForce(CalcCueForce(sim.path_, scene.haptic.max_force_N, s),
                                    scene.haptic.max_force_N, sim.dt_s_, s);

  // StepModules: reads the tool, writes each module's section and its force.
  ToolInput tool;
  tool.step = s.step;
  tool.dt_s = sim.dt_s_;
  tool.X_WT = s.tool.X_WT;
  tool.p_WT_device = s.tool.X_WT_device.translation();
  tool.second_tool = s.second_tool ? &*s.second_tool : nullptr;
  s.score.fault = 0;
  s.score.fault_value = 0;
  for (std::size_t i = 0; i < sim.modules_.size(); ++i) {
    Module& m = *sim.modules_[i];
    const std::int64_t t0 = sim.step_clock_ != nullptr ? sim.step_clock_->NowNs() : 0;
    m.Step(tool, s, f);
    if (sim.step_clock_ != nullptr) {
      sim.step_time_s_[i] = static_cast<double>(sim.step_clock_->NowNs() - t0) * 1e-9;
    }
    if (!s.score.fault) {
      const ModuleStatus st = m.Status(s);
      if (st.fault) {
        s.score.fault = 1;
        s.score.fault_value = st.fault_value;
      }
    }
  }

  // A device fault: the device gave the last valid pose again (held); the force goes to zero,
  // at the limiter's rate.
  Eigen::Vector3d tau = Eigen::Vector3d::Zero();
  for (const auto& m : sim.modules_) tau += m->ToolTorque(s);
  LimitToolWrench(f, tau, scene.haptic, sim.dt_s_, s.tool);
  if (s.second_tool) {
    Eigen::Vector3d f2 = Eigen::Vector3d::Zero();
    for (const auto& m : sim.modules_) f2 += m->SecondToolForce(s);
    LimitToolWrench(f2, Eigen::Vector3d::Zero(), scene.haptic, sim.dt_s_, *s.second_tool);
  }
  if (s.score.outcome == 0) {  // the scores freeze when the task ends
    UpdateScore(scene, sim.dt_s_, s);
    UpdateTask(scene, sim.path_, sim.dt_s_, s);
  } else {
    s.score.contact_event = 0;
  }
  UpdateCueSignals(scene, sim.path_, sim.predictor_, sim.dt_s_, s);
  ++s.step;
}

Eigen::Quaterniond CanonicalizeDeviceSample(DeviceSample& d) {
  Eigen::Quaterniond q(d.X_WT.linear());
  d.X_WT.linear() = q.toRotationMatrix();
  return q;
}

DeviceSample DeviceSampleFromRecord(const Eigen::Vector3d& p_WT, const Eigen::Quaterniond& q_WT,
                                    double gripper, std::uint32_t buttons) {
  DeviceSample d;
  d.X_WT.linear() = q_WT.toRotationMatrix();
  d.X_WT.translation() = p_WT;
  d.gripper = gripper;
  d.buttons = buttons;
  return d;
}

namespace {

Vec3 ToVec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Quat ToQuat(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.rotation());
  return {q.w(), q.x(), q.y(), q.z()};
}

}  // namespace

void ProjectSnapshot(const Simulation& sim, const state::StationState& s, TickSnapshot& out) {
  out.step = s.step - 1;  // the step just taken
  out.p_WT_device = ToVec3(s.tool.X_WT_device.translation());
  out.q_WT_device = ToQuat(s.tool.X_WT_device);
  out.gripper = s.tool.gripper;
  out.buttons = s.tool.buttons;
  out.p_WT = ToVec3(s.tool.X_WT.translation());
  out.q_WT = ToQuat(s.tool.X_WT);
  out.f_T_W = ToVec3(s.tool.f_T_W);
  out.has_second_tool = s.second_tool ? 1 : 0;
  if (s.second_tool) {
    const state::ToolState& t2 = *s.second_tool;
    out.second.p_WT_device = ToVec3(t2.X_WT_device.translation());
    out.second.q_WT_device = ToQuat(t2.X_WT_device);
    out.second.gripper = t2.gripper;
    out.second.buttons = t2.buttons;
    out.second.f_T_W = ToVec3(t2.f_T_W);
    out.second.device_fault = t2.device_fault;
  }
  out.active_cues = s.cues.active;
  CueSnapshot& cs = out.cue;
  cs.param = s.cues.param;
  cs.clearance_m = s.cues.clearance_m;
  cs.deviation_m = s.cues.deviation_m;
  cs.p_W_nearest = ToVec3(s.cues.p_W_nearest);
  cs.click = s.cues.click;
  cs.error = s.cues.error;
  cs.prediction_valid = s.cues.prediction.valid;
  cs.warning = s.cues.prediction.predictor.warning;
  cs.p_W_end = ToVec3(s.cues.prediction.p_W_end);
  cs.prediction_error_m = s.cues.prediction.error_m;
  cs.has_wall_points = 0;
  if (s.needle && s.needle->clearance.status == geometry::ClearanceStatus::kOk) {
    cs.has_wall_points = 1;
    cs.p_W_tool_near = ToVec3(s.needle->clearance.p_WD);
    cs.p_W_wall = ToVec3(s.needle->clearance.p_WB);
  } else if (s.loop && s.loop->clearance.status == geometry::LoopWireStatus::kOk) {
    cs.has_wall_points = 1;
    cs.p_W_tool_near = ToVec3(s.loop->clearance.p_WC);
    cs.p_W_wall = ToVec3(s.loop->clearance.p_WA);
  }
  out.has_needle = s.needle ? 1 : 0;
  if (s.needle) {
    const geometry::ArcTorusClearance& c = s.needle->clearance;
    const bool ok = c.status == geometry::ClearanceStatus::kOk;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    NeedleSnapshot& n = out.needle;
    n.p_WN = ToVec3(s.needle->X_WN.translation());
    n.q_WN = ToQuat(s.needle->X_WN);
    n.status = c.status;
    n.clearance_m = ok ? c.clearance_m : nan;
    n.contact = ok && c.contact ? 1 : 0;
    n.s_rad = ok ? c.s_rad : nan;
    n.p_WD = ToVec3(c.p_WD);
    n.p_WB = ToVec3(c.p_WB);
  }
  out.stitch_count = 0;
  if (s.placement) {
    const state::PlacementState& p = *s.placement;
    out.stitch_count = std::clamp(p.count, 0, state::kMaxStitches);
    for (int i = 0; i < out.stitch_count; ++i) {
      const auto k = static_cast<std::size_t>(i);
      out.stitch_azimuth_rad[k] = static_cast<float>(p.azimuth_rad[k]);
      out.stitch_bite_m[k] = static_cast<float>(p.bite_m[k]);
    }
  }
  out.has_tremor = s.tremor ? 1 : 0;
  if (s.tremor) {
    out.tremor_band_m = s.tremor->band_m;
    out.tremor_rms_m = std::sqrt(s.tremor->mean_square_m2);
  }
  out.module_count = static_cast<int>(sim.module_count());
  for (std::size_t i = 0; i < sim.module_count(); ++i) {
    const ModuleStatus st = sim.module(i).Status(s);
    out.modules[i] = {sim.last_step_time_s(i), st.error_estimate, st.warnings};
  }
  out.ack_count = s.cues.ack_count;
  for (int i = 0; i < s.cues.ack_count; ++i) out.acks[i] = s.cues.acks[i];
  out.fault = s.score.fault;
  out.fault_value = s.score.fault_value;
  out.contact_event = s.score.contact_event;
  out.force_warnings = s.tool.force_warnings;
  out.device_fault = s.tool.device_fault;
  out.score = s.score;
}

}  // namespace microdex::station
