#include "station/score.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace microdex::station {

net::Score CalcScore(const scene::SceneModel& scene, const state::ScoreState& t) {
  net::Score s;
  s.duration_s = t.time_s;
  s.time_in_contact_s = t.time_in_contact_s;
  s.contacts = t.contacts;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.mean_clearance_m =
      t.clearance_samples > 0 ? t.clearance_sum_m / static_cast<double>(t.clearance_samples) : nan;
  s.min_clearance_m = t.clearance_samples > 0 ? t.min_clearance_m : nan;
  s.path_length_m = t.path_length_m;
  s.ideal_path_length_m = t.ideal_path_length_m;
  s.tremor_rms_m = t.tremor_samples > 0
                       ? std::sqrt(t.tremor_sq_sum_m2 / static_cast<double>(t.tremor_samples))
                       : 0.0;
  if (t.time_s <= 0) {
    s.score = 0;
    return s;
  }
  const double contact_fraction = std::clamp(t.time_in_contact_s / t.time_s, 0.0, 1.0);
  if (!scene.HasModule("needle")) {
    // Thread and tissue tasks: the share of the time without fault.
    s.score = 100.0 * (1.0 - contact_fraction);
    return s;
  }
  if (t.clearance_samples == 0) {
    s.score = 0;
    return s;
  }
  const double g = std::clamp(s.mean_clearance_m / scene.vessel.tube_radius_m, 0.0, 1.0);
  s.score = 100.0 * (1.0 - contact_fraction) * (1.0 + g) / 2.0;
  return s;
}

}  // namespace microdex::station
