#pragma once
// The end point of the current sub-movement, extrapolated from past and present motion
// (thesis §2.1: "we will extrapolate the error at the end of a movement from the past and
// present states and signal it to the trainee, allowing early correction"; the visual loop's
// delay is 200 ms or more, so the warning must come earlier than the error can be seen).
//
// Model: a sub-movement is a minimum-jerk reach (Flash & Hogan) from p0 over a distance D in
// a time T: p(t) = p0 + D s(τ) u, τ = t / T, s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, so the distance
// travelled d = D s(τ), the speed v = D s'(τ) / T and the acceleration along u
// a = D s''(τ) / T², with s'(τ) = 30τ²(1 − τ)², s''(τ) = 60τ(1 − τ)(1 − 2τ). Their ratio
//     q = v² / (a d) = s'² / (s'' s) = 15 (1 − τ)³ / ((1 − 2τ)(10 − 15τ + 6τ²))
// depends on τ alone (1.5 at τ = 0, rising to +∞ at the peak speed τ = ½, then from −∞ back
// to 0 at τ = 1: one τ per value on each side of the peak, told apart by the sign of a) and
// needs neither D, nor T, nor when the movement started; then D = d / s(τ) and the end point is
// p0 + D u, u the direction from p0 to the tool. A low-pass filter's lag delays the smoothed
// reach but does not change where it ends. (An earlier version used r = d / (v t), which needs
// the start time: the onset of a slow reach under tremor is found tens of milliseconds late, and
// the error of t biased every early prediction.)
//
// The sub-movement starts when the smoothed speed rises above onset_speed; p0 is the last
// position where the speed was below quiet_speed (the reach has covered well under 1 % of its
// distance there); it ends when the speed stays below stop_speed for stop_s. Positions are
// smoothed by a 2nd-order Butterworth low-pass (the tremor band is noise here); predictions
// count from τ >= min_tau, when the ratio is well conditioned.
//
// Plain state, no allocation: safe in the haptic tick.

#include <Eigen/Core>
#include <cstdint>

#include "common/cues/tremor_filter.h"

namespace microdex::cues {

struct EndPointPredictorDef {
  double sample_rate_hz = 1000;
  double smoothing_hz = 4;              // low-pass corner on position, Hz
  double quiet_speed_m_per_s = 0.4e-3;  // at rest below this speed (tremor filtered out)
  double onset_speed_m_per_s = 1.5e-3;  // a sub-movement starts above this speed
  double stop_speed_m_per_s = 0.75e-3;  // and ends after stop_s below this one
  double stop_s = 0.06;
  double min_tau = 0.45;           // a prediction is valid from this fraction of the movement on
  double min_distance_m = 0.3e-3;  // and once the tool moved this far
  // Throws std::invalid_argument("field: reason").
  void Validate() const;
};

struct EndPointPredictorModel {
  EndPointPredictorDef def;
  Biquad low_pass;
};
EndPointPredictorModel MakeEndPointPredictor(const EndPointPredictorDef& def);

// Lives in state::StationState (CueState::prediction): every field is state.
struct EndPointPredictorState {
  Eigen::Vector3d lp_z1 = Eigen::Vector3d::Zero(), lp_z2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_prev = Eigen::Vector3d::Zero();   // smoothed position, previous step
  Eigen::Vector3d v_prev = Eigen::Vector3d::Zero();   // smoothed velocity, previous step
  Eigen::Vector3d p_start = Eigen::Vector3d::Zero();  // start of the sub-movement (at rest:
                                                      // the last quiet position)
  std::uint8_t started = 0;
  std::uint8_t moving = 0;   // a sub-movement is under way
  double t_s = 0;            // time since that start (for the views; not used by the model)
  double still_s = 0;        // time below stop_speed
  double over_s = 0;         // time the predicted error has been beyond the limit
  std::uint8_t warning = 0;  // StepPredictiveWarning's output
};

struct EndPointPrediction {
  bool valid = false;  // a sub-movement under way, far enough along for a prediction
  Eigen::Vector3d p_W_end = Eigen::Vector3d::Zero();
  double tau = 0;  // estimated fraction of the movement done
};

// The minimum-jerk phase τ in [0, 1) of the ratio q = v² / (a d) = s'² / (s'' s): q > 1.5
// before the peak speed (a > 0), q < 0 after it; 0 for q in (0, 1.5] or NaN.
double CalcMinimumJerkPhaseFromAcceleration(double q);

// Feeds one tool position (m); returns the prediction for this step. Non-finite input
// restarts the predictor (no prediction that step).
EndPointPrediction StepEndPointPredictor(const EndPointPredictorModel& model,
                                         const Eigen::Vector3d& p_W, EndPointPredictorState& state);

// The predictive cue's warning: raised once the predicted end point's error (its distance from
// the target or the path) has stayed above limit_m for kWarningConfirm_s, dropped when it falls
// below kWarningRelease · limit_m or when the sub-movement ends. Returns the warning.
inline constexpr double kWarningConfirm_s = 0.05;
inline constexpr double kWarningRelease = 0.8;
bool StepPredictiveWarning(const EndPointPrediction& prediction, double error_m, double limit_m,
                           double dt_s, EndPointPredictorState& state);

}  // namespace microdex::cues
