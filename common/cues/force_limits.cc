#include "common/cues/force_limits.h"

namespace microdex::cues {

ForceLimitResult LimitForce(const Eigen::Vector3d& f_request_N, const Eigen::Vector3d& f_prev_N,
                            double max_force_N, double max_rate_N_per_s, double dt_s) {
  ForceLimitResult r;
  const Eigen::Vector3d prev = f_prev_N.allFinite() ? f_prev_N : Eigen::Vector3d::Zero();
  Eigen::Vector3d f = f_request_N;
  if (!f.allFinite()) {
    r.non_finite = true;
    f = prev;
  }
  const double max_step = max_rate_N_per_s * dt_s;
  const Eigen::Vector3d df = f - prev;
  const double dn = df.norm();
  if (dn > max_step) {
    f = prev + df * (max_step / dn);
    r.rate_limited = true;
  }
  const double fn = f.norm();
  if (fn > max_force_N) f *= max_force_N / fn;
  r.f_N = f;
  return r;
}

}  // namespace microdex::cues
