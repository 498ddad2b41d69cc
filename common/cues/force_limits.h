#pragma once
// The last stage before a force reaches a device: whatever the cues and the modules asked for,
// the force sent is finite, no larger than max_force_N and changes by no more than
// max_rate_N_per_s · dt from one step to the next. The magnitude bound keeps the energy a
// cue can inject per step bounded; the rate bound turns a spring too stiff for the device
// (k T² / m beyond the stability limit of a sampled spring, e.g. 1e6 N/m at 1 kHz) into a
// bounded, slowly reversing push instead of a step-to-step bang-bang, so no cue parameter
// within its limits (cue_kind.h) can make the device unstable (tests/unit/cues).
//
// Pure functions, no allocation: safe in the haptic tick.

#include <Eigen/Core>

namespace microdex::cues {

// 2 N (the scenes' saturation) in 2 ms at most.
inline constexpr double kMaxForceRate_N_per_s = 1000;

struct ForceLimitResult {
  Eigen::Vector3d f_N = Eigen::Vector3d::Zero();
  bool non_finite = false;    // the request was not finite (replaced by the previous force)
  bool rate_limited = false;  // the change was clipped
};

// The force to send this step given the requested one and the one sent the step before:
// a non-finite request holds the previous force; the change is clipped to max_rate·dt; the
// result is saturated at max_force_N. A non-finite previous force counts as zero.
ForceLimitResult LimitForce(const Eigen::Vector3d& f_request_N, const Eigen::Vector3d& f_prev_N,
                            double max_force_N, double max_rate_N_per_s, double dt_s);

}  // namespace microdex::cues
