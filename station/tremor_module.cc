#include "station/tremor_module.h"

#include <cmath>

namespace microdex::station {

TremorModule::TremorModule(const scene::SceneModel& scene) {
  cues::TremorFilterDef def;
  def.sample_rate_hz = scene.haptic.rate_hz;
  filter_ = cues::MakeTremorFilter(def);
  alpha_ = 1.0 - std::exp(-1.0 / (kRmsWindow_s * scene.haptic.rate_hz));
}

void TremorModule::Step(const ToolInput& in, Eigen::Vector3d& /*f_T_W*/) {
  const Eigen::Vector3d band = cues::StepTremorFilter(filter_, in.p_WT_device, state_);
  band_m_ = band.norm();
  mean_square_m2_ += alpha_ * (band.squaredNorm() - mean_square_m2_);
}

void TremorModule::WriteSnapshot(TickSnapshot& s) const {
  s.has_tremor = 1;
  s.tremor_band_m = band_m_;
  s.tremor_rms_m = rms_m();
}

}  // namespace microdex::station
