#pragma once
// The physiological-tremor band (8–12 Hz) of a tool position: a 2nd-order Butterworth
// high-pass at 6 Hz cascaded with a 2nd-order Butterworth low-pass at 16 Hz (bilinear
// transform, RBJ cookbook biquads). The high-pass is 2nd order so that a constant-velocity
// motion (a ramp) leaves no steady offset: the intended motion of a pass (minimum jerk, a few
// seconds) barely enters the band. Used by the tremor module (measurement) and the amplified
// tremor cue (thesis §2.1: "amplified tremor can help micromanipulation learning").
//
// Plain state, no allocation: safe in the haptic tick.

#include <Eigen/Core>

namespace microdex::cues {

struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;  // normalised by a0
};

// 2nd-order Butterworth (Q = 1/√2) sections at corner f0_hz for sample rate fs_hz.
Biquad MakeButterworthLowPass(double f0_hz, double fs_hz);
Biquad MakeButterworthHighPass(double f0_hz, double fs_hz);

struct TremorFilterDef {
  double high_pass_hz = 6.0;
  double low_pass_hz = 16.0;
  double sample_rate_hz = 1000.0;
  // Throws std::invalid_argument("field: reason") (the contract of every Def's Validate()).
  void Validate() const;
};

struct TremorFilterModel {
  Biquad high_pass;
  Biquad low_pass;
};
TremorFilterModel MakeTremorFilter(const TremorFilterDef& def);

// Direct form II transposed state of both sections, per axis.
struct TremorFilterState {
  Eigen::Vector3d hp_z1 = Eigen::Vector3d::Zero(), hp_z2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d lp_z1 = Eigen::Vector3d::Zero(), lp_z2 = Eigen::Vector3d::Zero();
  bool started = false;
};

// Feeds one position sample (m); returns the band-passed position (m). The first sample
// initialises the state as if the input had been constant before (no start-up transient).
Eigen::Vector3d StepTremorFilter(const TremorFilterModel& model, const Eigen::Vector3d& p,
                                 TremorFilterState& state);

}  // namespace microdex::cues
