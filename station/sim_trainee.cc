#include "station/sim_trainee.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace microdex::station {
namespace {
constexpr double kTwoPi = 6.283185307179586;
double Lerp(double novice, double expert, double skill) {
  return novice + (expert - novice) * skill;
}
}  // namespace

void SimTraineeDef::Validate() const {
  if (!(skill >= 0 && skill <= 1)) throw std::invalid_argument("skill: expected 0..1");
  if (!(tremor_rms_novice_m >= 0 && tremor_rms_expert_m >= 0))
    throw std::invalid_argument("tremor_rms: expected >= 0");
  if (!(drift_std_novice_m >= 0 && drift_std_expert_m >= 0))
    throw std::invalid_argument("drift_std: expected >= 0");
  if (!(drift_min_hz > 0 && drift_min_hz < drift_max_hz)) {
    throw std::invalid_argument("drift_min_hz: expected 0 < drift_min_hz < drift_max_hz");
  }
  if (!(pace_novice > 0 && pace_expert > 0 && pace_novice <= 10 && pace_expert <= 10)) {
    throw std::invalid_argument("pace: expected (0, 10]");
  }
  if (!(reaction_delay_novice_s >= 0 && reaction_delay_expert_s >= 0 &&
        reaction_delay_novice_s <= 2 && reaction_delay_expert_s <= 2)) {
    throw std::invalid_argument("reaction_delay_s: expected 0..2 s");
  }
  if (!(correction_threshold_novice_m > 0 && correction_threshold_expert_m > 0)) {
    throw std::invalid_argument("correction_threshold_m: expected > 0");
  }
  if (!(correction_duration_s > 0 && correction_duration_s <= 2)) {
    throw std::invalid_argument("correction_duration_s: expected (0, 2] s");
  }
  if (!(square_rule_skill >= 0 && square_rule_skill <= 1)) {
    throw std::invalid_argument("square_rule_skill: expected 0..1");
  }
  if (!(hand_stiffness_N_per_m > 0))
    throw std::invalid_argument("hand_stiffness_N_per_m: expected > 0");
  if (!(hand_time_constant_s > 0))
    throw std::invalid_argument("hand_time_constant_s: expected > 0");
  if (hand != 0 && hand != 1) throw std::invalid_argument("hand: expected 0 or 1");
}

SimTrainee::SimTrainee(const scene::SceneModel& scene, const SimTraineeDef& def)
    : scene_(scene),
      dt_s_(1.0 / scene.haptic.rate_hz),
      tremor_rms_m_(Lerp(def.tremor_rms_novice_m, def.tremor_rms_expert_m, def.skill)),
      drift_std_m_(Lerp(def.drift_std_novice_m, def.drift_std_expert_m, def.skill)),
      drift_std_rad_(Lerp(def.drift_std_novice_rad, def.drift_std_expert_rad, def.skill)),
      hand_stiffness_N_per_m_(def.hand_stiffness_N_per_m),
      hand_time_constant_s_(std::max(def.hand_time_constant_s, 1.0 / scene.haptic.rate_hz)),
      pace_(Lerp(def.pace_novice, def.pace_expert, def.skill)),
      reaction_delay_s_(Lerp(def.reaction_delay_novice_s, def.reaction_delay_expert_s, def.skill)),
      correction_threshold_m_(
          Lerp(def.correction_threshold_novice_m, def.correction_threshold_expert_m, def.skill)),
      correction_duration_s_(def.correction_duration_s),
      close_duration_s_(def.close_duration_s),
      hand_(def.hand) {
  // All randomness is drawn here, from the seed; Read() is a pure function of the step and
  // the previous force. SplitMix64 rather than <random> distributions, whose algorithms the
  // standard leaves to the library: the samples are then the same on every platform.
  // The second hand: a stream of its own (the golden-ratio increment's odd multiple away).
  std::uint64_t state = def.seed + (hand_ == 1 ? 0xD1B54A32D192ED03ULL : 0);
  auto uniform = [&state](double lo, double hi) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return lo + (hi - lo) * static_cast<double>(z >> 11) * 0x1.0p-53;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int c = 0; c < kTremorComponents; ++c) {
      freq_hz_[axis][c] = uniform(8.0, 12.0);
      phase_rad_[axis][c] = uniform(0.0, kTwoPi);
    }
  }
  for (int axis = 0; axis < 6; ++axis) {
    for (int c = 0; c < kDriftComponents; ++c) {
      drift_freq_hz_[axis][c] = uniform(def.drift_min_hz, def.drift_max_hz);
      drift_phase_rad_[axis][c] = uniform(0.0, kTwoPi);
    }
  }
  // The jaws' misalignment (grasp): a misjudgement of about the skill's size, either way, within
  // ±20 % of it.
  const double yaw = Lerp(def.jaw_yaw_novice_rad, def.jaw_yaw_expert_rad, def.skill);
  const double offset = Lerp(def.jaw_offset_novice_m, def.jaw_offset_expert_m, def.skill);
  const auto either_way = [&uniform](double size) {
    const double sign = uniform(-1.0, 1.0) < 0 ? -1.0 : 1.0;
    return sign * size * uniform(0.8, 1.2);
  };
  jaw_yaw_rad_ = either_way(yaw);
  jaw_offset_m_ = either_way(offset);
  if (hand_ == 1) return;  // the task's buttons and stitches belong to the first hand
  if (scene.task.kind == scene::TaskKind::kKnotPlacement && scene.placement) {
    const scene::PlacementSceneDef& p = *scene.placement;
    const double angle_sd =
        Lerp(def.placement_angle_novice_rad, def.placement_angle_expert_rad, def.skill);
    const double bite_sd =
        Lerp(def.placement_bite_novice_m, def.placement_bite_expert_m, def.skill);
    for (int k = 0; k < p.stitches; ++k) {
      stitch_azimuth_rad_.push_back(kTwoPi * k / p.stitches +
                                    std::sqrt(3.0) * angle_sd * uniform(-1.0, 1.0));
      stitch_z_m_.push_back(p.end_height_m - p.bite_m -
                            std::sqrt(3.0) * bite_sd * uniform(-1.0, 1.0));
    }
  }
  if (scene.task.kind == scene::TaskKind::kKnotTying && scene.knot_tying && def.hand == 0) {
    // Each throw chosen after a response time; the first throw's hand drawn from the seed, the
    // next ones of the opposite hand (square) or, below square_rule_skill, of the same hand
    // (the granny habit).
    const double rt = Lerp(def.response_time_novice_s, def.response_time_expert_s, def.skill);
    const bool first_right = uniform(0.0, 1.0) < 0.5;
    const bool alternate = def.skill >= def.square_rule_skill;
    double t = 0;
    for (int k = 0; k < scene.knot_tying->throws; ++k) {
      t += rt * uniform(0.8, 1.2);
      press_s_.push_back(t);
      const bool right = (k % 2 == 0 || !alternate) ? first_right : !first_right;
      answer_.push_back(right ? 1u : 2u);
    }
  }
  if (scene.task.kind == scene::TaskKind::kKnotTopology && scene.knots) {
    const std::vector<knot::StitchKnotType>& items = scene.knots->items;
    const std::size_t n = items.size();
    const double accuracy = Lerp(def.accuracy_novice, def.accuracy_expert, def.skill);
    const auto wrong = static_cast<std::size_t>(std::lround((1.0 - accuracy) * n));
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    for (std::size_t i = n; i > 1; --i) {  // Fisher–Yates from the seed
      const auto j = std::min(static_cast<std::size_t>(uniform(0.0, 1.0) * i), i - 1);
      std::swap(order[i - 1], order[j]);
    }
    std::vector<bool> is_wrong(n, false);
    for (std::size_t i = 0; i < std::min(wrong, n); ++i) is_wrong[order[i]] = true;
    const double rt = Lerp(def.response_time_novice_s, def.response_time_expert_s, def.skill);
    double t = 0;
    for (std::size_t i = 0; i < n; ++i) {
      t += rt * uniform(0.8, 1.2);
      press_s_.push_back(t);
      knot::StitchKnotType named = items[i];
      if (is_wrong[i]) {
        switch (items[i]) {
          case knot::StitchKnotType::kSquare:
            named = knot::StitchKnotType::kGranny;
            break;
          case knot::StitchKnotType::kGranny:
          case knot::StitchKnotType::kSurgeons:
            named = knot::StitchKnotType::kSquare;
            break;
          case knot::StitchKnotType::kSlip:
            named = knot::StitchKnotType::kHalfHitch;
            break;
          default:
            named = knot::StitchKnotType::kSlip;
            break;
        }
      }
      answer_.push_back(static_cast<std::uint32_t>(named));
    }
  }
}

Eigen::Vector3d SimTrainee::CalcDrift(double t_s, Eigen::Vector3d* drift_rad) const {
  // n sinusoids of amplitude b have standard deviation b √(n/2).
  const double drift_scale = 1.0 / std::sqrt(kDriftComponents / 2.0);
  Eigen::Vector3d drift_m;
  for (int axis = 0; axis < 6; ++axis) {
    if (axis >= 3 && drift_rad == nullptr) break;
    double sum = 0;
    for (int c = 0; c < kDriftComponents; ++c) {
      sum += std::sin(kTwoPi * drift_freq_hz_[axis][c] * t_s + drift_phase_rad_[axis][c]);
    }
    if (axis < 3) {
      drift_m[axis] = drift_std_m_ * drift_scale * sum;
    } else {
      (*drift_rad)[axis - 3] = drift_std_rad_ * drift_scale * sum;
    }
  }
  return drift_m;
}

Eigen::Vector3d SimTrainee::CalcCorrection(double t_s) const {
  const double tau = std::clamp((t_s - correction_start_s_) / correction_duration_s_, 0.0, 1.0);
  const double shape = tau * tau * tau * (10 + tau * (-15 + 6 * tau));
  return correction_from_m_ + shape * (correction_to_m_ - correction_from_m_);
}

Eigen::Isometry3d SimTrainee::CalcPlannedPose(double t_s, double* gripper) const {
  *gripper = 0;
  if (hand_ == 1) {
    *gripper = 1;
    return scene_.CalcIdealSecondToolPose(t_s);
  }
  if (!stitch_azimuth_rad_.empty()) {
    // Stitch k: at rest over [k T, k T + 0.3 T], then on to stitch k + 1 by (k + 1) T.
    const double T = scene_.placement->move_s / pace_;
    const auto n = static_cast<int>(stitch_azimuth_rad_.size());
    const int k = std::clamp(static_cast<int>(std::floor(t_s / T)), 0, n - 1);
    const double tau = std::clamp((t_s - k * T - 0.3 * T) / (0.7 * T), 0.0, 1.0);
    const double shape = tau * tau * tau * (10 + tau * (-15 + 6 * tau));
    const int next = std::min(k + 1, n - 1);
    const double azimuth =
        stitch_azimuth_rad_[k] + shape * (stitch_azimuth_rad_[next] - stitch_azimuth_rad_[k]);
    const double z = stitch_z_m_[k] + shape * (stitch_z_m_[next] - stitch_z_m_[k]);
    const double r = scene_.placement->vessel_radius_m;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(r * std::cos(azimuth), r * std::sin(azimuth), z);
    return X;
  }
  if (scene_.task.kind != scene::TaskKind::kGrasp) return scene_.CalcIdealToolPose(pace_ * t_s);
  // Descend (one pass), close, lift (the return pass), hold at the top.
  const double pass_s = scene_.task.pass_duration_s / pace_;
  const double close_s = close_duration_s_ / pace_;
  double plan_s = 0;  // time along the scene's passes
  if (t_s < pass_s) {
    plan_s = t_s;
  } else if (t_s < pass_s + close_s) {
    plan_s = pass_s;
    const double tau = (t_s - pass_s) / close_s;
    *gripper = tau * tau * tau * (10 + tau * (-15 + 6 * tau));
  } else {
    plan_s = std::min(t_s - close_s, 2 * pass_s);
    *gripper = 1;
  }
  Eigen::Isometry3d X = scene_.CalcIdealToolPose(pace_ * plan_s);
  if (plan_s >= 2 * pass_s) X = scene_.CalcIdealToolPose(0);  // back at the start, holding
  X.linear() = X.linear() * Eigen::AngleAxisd(jaw_yaw_rad_, Eigen::Vector3d::UnitZ()).matrix();
  X.translation() += X.linear().col(0) * jaw_offset_m_;
  return X;
}

DeviceSample SimTrainee::Read(std::uint64_t step) {
  const double t = static_cast<double>(step) * dt_s_;
  // Each of the three components has amplitude a, RMS a/√2; three independent ones: RMS
  // a √(3/2) = tremor_rms_m.
  const double amplitude = tremor_rms_m_ / std::sqrt(1.5);
  Eigen::Vector3d tremor;
  for (int axis = 0; axis < 3; ++axis) {
    double sum = 0;
    for (int c = 0; c < kTremorComponents; ++c) {
      sum += std::sin(kTwoPi * freq_hz_[axis][c] * t + phase_rad_[axis][c]);
    }
    tremor[axis] = amplitude * sum;
  }
  Eigen::Vector3d drift_rad;
  const Eigen::Vector3d drift_m = CalcDrift(t, &drift_rad);
  // A corrective sub-movement starts when none is under way and the drift seen τ_r ago, less
  // the corrections made, is beyond the threshold.
  Eigen::Vector3d correction = CalcCorrection(t);
  if (t - correction_start_s_ >= correction_duration_s_ && t >= reaction_delay_s_) {
    // What was seen, extrapolated by the velocity seen over the delay and half the movement
    // (the hand's internal model predicts where the drift will be).
    const double lead_s = reaction_delay_s_ + 0.5 * correction_duration_s_;
    const double h = 0.01;
    const Eigen::Vector3d d0 = CalcDrift(t - reaction_delay_s_, nullptr);
    const Eigen::Vector3d d1 = CalcDrift(t - reaction_delay_s_ - h, nullptr);
    const Eigen::Vector3d seen = d0 + (lead_s / h) * (d0 - d1) - correction;
    if (seen.norm() > correction_threshold_m_) {
      correction_from_m_ = correction;
      correction_to_m_ = correction + seen;
      correction_start_s_ = t;
    }
  }
  DeviceSample sample;
  const Eigen::Isometry3d X_ideal = CalcPlannedPose(t, &sample.gripper);
  // Knot placement: a button pressed at each stitch's rest, from 0.1 T to 0.2 T.
  if (!stitch_azimuth_rad_.empty()) {
    const double T = scene_.placement->move_s / pace_;
    const double phase = t / T - std::floor(t / T);
    if (t < static_cast<double>(stitch_azimuth_rad_.size()) * T && phase >= 0.1 && phase < 0.2) {
      sample.buttons = 1;
    }
  }
  // Knot topology: the button of the answer, held for kPress_s.
  constexpr double kPress_s = 0.1;
  while (next_answer_ < press_s_.size() && t >= press_s_[next_answer_] + kPress_s) ++next_answer_;
  if (next_answer_ < press_s_.size() && t >= press_s_[next_answer_]) {
    sample.buttons = answer_[next_answer_];
  }
  sample.X_WT = X_ideal;
  const double angle = drift_rad.norm();
  if (angle > 0) {
    sample.X_WT.linear() = X_ideal.linear() * Eigen::AngleAxisd(angle, drift_rad / angle).matrix();
  }
  hand_offset_m_ +=
      (dt_s_ / hand_time_constant_s_) * (f_prev_W_ / hand_stiffness_N_per_m_ - hand_offset_m_);
  sample.X_WT.translation() =
      X_ideal.translation() + tremor + drift_m - correction + hand_offset_m_;
  return sample;
}

}  // namespace microdex::station
