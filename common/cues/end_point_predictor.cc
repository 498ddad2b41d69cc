#include "common/cues/end_point_predictor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace microdex::cues {

void EndPointPredictorDef::Validate() const {
  if (!(sample_rate_hz > 0 && std::isfinite(sample_rate_hz))) {
    throw std::invalid_argument("sample_rate_hz: expected > 0");
  }
  if (!(smoothing_hz > 0 && smoothing_hz < sample_rate_hz / 2)) {
    throw std::invalid_argument("smoothing_hz: expected 0 < smoothing_hz < Nyquist");
  }
  if (!(quiet_speed_m_per_s > 0 && quiet_speed_m_per_s <= stop_speed_m_per_s)) {
    throw std::invalid_argument("quiet_speed_m_per_s: expected 0 < quiet <= stop speed");
  }
  if (!(stop_speed_m_per_s > 0 && stop_speed_m_per_s <= onset_speed_m_per_s)) {
    throw std::invalid_argument("stop_speed_m_per_s: expected 0 < stop <= onset speed");
  }
  if (!(stop_s > 0 && std::isfinite(stop_s))) throw std::invalid_argument("stop_s: expected > 0");
  if (!(min_tau >= 0 && min_tau < 1)) throw std::invalid_argument("min_tau: expected [0, 1)");
  if (!(min_distance_m >= 0 && std::isfinite(min_distance_m))) {
    throw std::invalid_argument("min_distance_m: expected >= 0");
  }
}

EndPointPredictorModel MakeEndPointPredictor(const EndPointPredictorDef& def) {
  def.Validate();
  return {def, MakeButterworthLowPass(def.smoothing_hz, def.sample_rate_hz)};
}

double CalcMinimumJerkPhaseFromAcceleration(double q) {
  if (std::isnan(q)) return 0;
  // h(τ) = s'² / (s'' s) = 15 (1 − τ)³ / ((1 − 2τ)(10 − 15τ + 6τ²)): 1.5 at τ = 0, +∞ at
  // τ → 0.5⁻, −∞ at 0.5⁺, 0⁻ at τ = 1; increasing on each branch. Bisection on the branch of
  // q's sign.
  const auto h = [](double t) {
    return 15 * (1 - t) * (1 - t) * (1 - t) / ((1 - 2 * t) * (10 - 15 * t + 6 * t * t));
  };
  if (q > 0 && q <= 1.5) return 0;
  double lo = q > 0 ? 0.0 : 0.5, hi = q > 0 ? 0.5 : 1.0;
  for (int i = 0; i < 48; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (h(mid) < q) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

EndPointPrediction StepEndPointPredictor(const EndPointPredictorModel& model,
                                         const Eigen::Vector3d& p_W, EndPointPredictorState& s) {
  const EndPointPredictorDef& def = model.def;
  const double dt = 1 / def.sample_rate_hz;
  EndPointPrediction out;
  if (!p_W.allFinite()) {
    s = EndPointPredictorState{};
    return out;
  }
  const Biquad& f = model.low_pass;
  if (!s.started) {              // steady state for a constant input p_W
    s.lp_z1 = (1 - f.b0) * p_W;  // y = b0 x + z1 = x
    s.lp_z2 = (f.b2 - f.a2) * p_W;
    s.p_prev = p_W;
    s.v_prev.setZero();
    s.started = 1;
  }
  // Direct form II transposed, as the tremor filter.
  const Eigen::Vector3d p = f.b0 * p_W + s.lp_z1;
  s.lp_z1 = f.b1 * p_W - f.a1 * p + s.lp_z2;
  s.lp_z2 = f.b2 * p_W - f.a2 * p;
  const Eigen::Vector3d v = (p - s.p_prev) / dt;
  const Eigen::Vector3d a = (v - s.v_prev) / dt;
  s.p_prev = p;
  s.v_prev = v;
  const double speed = v.norm();

  if (!s.moving) {
    // At rest: p_start and t_s follow the last moment the tool was quiet.
    if (speed < def.quiet_speed_m_per_s) {
      s.p_start = p;
      s.t_s = 0;
    } else {
      s.t_s += dt;
    }
    if (speed > def.onset_speed_m_per_s) {
      s.moving = 1;
      s.still_s = 0;
    }
    return out;
  }
  s.t_s += dt;
  if (speed < def.stop_speed_m_per_s) {
    s.still_s += dt;
    if (s.still_s >= def.stop_s) {
      s.moving = 0;
      return out;
    }
  } else {
    s.still_s = 0;
  }
  const Eigen::Vector3d d_vec = p - s.p_start;
  const double d = d_vec.norm();
  if (d < def.min_distance_m || d < 1e-12) return out;
  const Eigen::Vector3d u = d_vec / d;
  const double v_along = v.dot(u);
  if (!(v_along > 0)) return out;  // not moving away from the start
  const double a_along = a.dot(u);
  const double tau = CalcMinimumJerkPhaseFromAcceleration(v_along * v_along / (a_along * d));
  if (tau < def.min_tau || tau >= 1) return out;
  const double sv = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
  out.valid = true;
  out.tau = tau;
  out.p_W_end = s.p_start + (d / sv) * u;
  return out;
}

bool StepPredictiveWarning(const EndPointPrediction& prediction, double error_m, double limit_m,
                           double dt_s, EndPointPredictorState& s) {
  if (!s.moving) {
    s.warning = 0;
    s.over_s = 0;
    return false;
  }
  if (prediction.valid) {
    s.over_s = error_m > limit_m ? s.over_s + dt_s : 0.0;
    if (s.over_s >= kWarningConfirm_s - 1e-12) s.warning = 1;
    if (error_m < kWarningRelease * limit_m) s.warning = 0;
  }
  return s.warning != 0;
}

}  // namespace microdex::cues
