#pragma once
// The tremor module: measures the trainee's physiological tremor — the 8–12 Hz band of the
// raw device motion, which the station filters once per step for every scene
// (state.cues.tremor_band_m, common/cues/tremor_filter.h) — as a running RMS over about one
// second. Feeds the tool state (tremor_rms_m), the score, and the "tremor control" primitive
// (thesis §2.2, Fig. 2.2a). It adds no force. State: state::TremorState.

#include "station/module.h"

namespace microdex::station {

class TremorModule final : public Module {
 public:
  static constexpr double kRmsWindow_s = 1.0;

  explicit TremorModule(const scene::SceneModel& scene);
  const char* name() const override { return "tremor"; }
  void InitState(state::StationState& state) const override { state.tremor.emplace(); }
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;

 private:
  double alpha_;  // exponential-average weight per step
};

}  // namespace microdex::station
