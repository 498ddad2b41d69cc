#include "station/tremor_module.h"

#include <cmath>

namespace microdex::station {

TremorModule::TremorModule(const scene::SceneModel& scene)
    : alpha_(1.0 - std::exp(-1.0 / (kRmsWindow_s * scene.haptic.rate_hz))) {}

void TremorModule::Step(const ToolInput& /*in*/, state::StationState& s,
                        Eigen::Vector3d& /*f_T_W*/) {
  state::TremorState& t = *s.tremor;
  const Eigen::Vector3d& band = s.cues.tremor_band_m;
  t.band_m = band.norm();
  t.mean_square_m2 += alpha_ * (band.squaredNorm() - t.mean_square_m2);
}

ModuleStatus TremorModule::Status(const state::StationState& /*s*/) const { return {}; }

}  // namespace microdex::station
