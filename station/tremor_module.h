#pragma once
// The tremor module: measures the trainee's physiological tremor (the 8–12 Hz band of the raw
// device motion, common/cues/tremor_filter.h) as a running RMS over about one second. Feeds
// the tool state (tremor_rms_m), the score, and the "tremor control" primitive (thesis §2.2,
// Fig. 2.2a). It adds no force.

#include "common/cues/tremor_filter.h"
#include "station/module.h"

namespace microdex::station {

class TremorModule final : public Module {
 public:
  static constexpr double kRmsWindow_s = 1.0;

  explicit TremorModule(const scene::SceneModel& scene);
  const char* name() const override { return "tremor"; }
  void Step(const ToolInput& in, Eigen::Vector3d& f_T_W) override;
  void WriteSnapshot(TickSnapshot& snapshot) const override;

  double rms_m() const { return std::sqrt(mean_square_m2_); }

 private:
  cues::TremorFilterModel filter_;
  cues::TremorFilterState state_;
  double alpha_;  // exponential-average weight per step
  double band_m_ = 0;
  double mean_square_m2_ = 0;
};

}  // namespace microdex::station
