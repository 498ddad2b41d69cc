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
  if (!(hand_stiffness_N_per_m > 0))
    throw std::invalid_argument("hand_stiffness_N_per_m: expected > 0");
  if (!(hand_time_constant_s > 0))
    throw std::invalid_argument("hand_time_constant_s: expected > 0");
}

SimTrainee::SimTrainee(const scene::SceneModel& scene, const SimTraineeDef& def)
    : scene_(scene),
      dt_s_(1.0 / scene.haptic.rate_hz),
      tremor_rms_m_(Lerp(def.tremor_rms_novice_m, def.tremor_rms_expert_m, def.skill)),
      drift_std_m_(Lerp(def.drift_std_novice_m, def.drift_std_expert_m, def.skill)),
      drift_std_rad_(Lerp(def.drift_std_novice_rad, def.drift_std_expert_rad, def.skill)),
      hand_stiffness_N_per_m_(def.hand_stiffness_N_per_m),
      hand_time_constant_s_(std::max(def.hand_time_constant_s, 1.0 / scene.haptic.rate_hz)) {
  // All randomness is drawn here, from the seed; Read() is a pure function of the step and
  // the previous force. SplitMix64 rather than <random> distributions, whose algorithms the
  // standard leaves to the library: the samples are then the same on every platform.
  std::uint64_t state = def.seed;
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
  // Drift: n sinusoids of amplitude b have standard deviation b √(n/2).
  const double drift_scale = 1.0 / std::sqrt(kDriftComponents / 2.0);
  Eigen::Vector3d drift_m, drift_rad;
  for (int axis = 0; axis < 6; ++axis) {
    double sum = 0;
    for (int c = 0; c < kDriftComponents; ++c) {
      sum += std::sin(kTwoPi * drift_freq_hz_[axis][c] * t + drift_phase_rad_[axis][c]);
    }
    if (axis < 3) {
      drift_m[axis] = drift_std_m_ * drift_scale * sum;
    } else {
      drift_rad[axis - 3] = drift_std_rad_ * drift_scale * sum;
    }
  }
  const Eigen::Isometry3d X_ideal = scene_.CalcIdealToolPose(t);
  DeviceSample sample;
  sample.X_WT = X_ideal;
  const double angle = drift_rad.norm();
  if (angle > 0) {
    sample.X_WT.linear() = X_ideal.linear() * Eigen::AngleAxisd(angle, drift_rad / angle).matrix();
  }
  hand_offset_m_ +=
      (dt_s_ / hand_time_constant_s_) * (f_prev_W_ / hand_stiffness_N_per_m_ - hand_offset_m_);
  sample.X_WT.translation() = X_ideal.translation() + tremor + drift_m + hand_offset_m_;
  return sample;
}

}  // namespace microdex::station
