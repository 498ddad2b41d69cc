#pragma once
// The knot-topology module (thesis §2.2, Fig. 2.2f: "differentiating a topologically correct
// surgical knot from incorrect ones can be learned separately"): the scene's knots, tied around
// a stitch (common/knot/stitch_knot_shapes.h), are shown one at a time; the trainee names each
// by pressing the device's button whose value is the knot's class (1 square, 2 granny,
// 3 surgeon's, 4 slip, 5 half hitch), the next knot appearing at once. Each knot's shape has
// been checked by the stitch-knot recogniser when the scene was loaded (scene::LoadScene), so
// a trainee is never asked to name a knot the recogniser would call otherwise. Adds no force.
// State: state::KnotQuizState.

#include <Eigen/Core>
#include <vector>

#include "common/knot/stitch_knot.h"
#include "station/module.h"

namespace microdex::station {

class KnotQuizModule final : public Module {
 public:
  explicit KnotQuizModule(const scene::SceneModel& scene);
  const char* name() const override { return "knots"; }
  void InitState(state::StationState& state) const override { state.knots.emplace(); }
  void Step(const ToolInput& in, state::StationState& state, Eigen::Vector3d& f_T_W) override;
  ModuleStatus Status(const state::StationState& state) const override;

  // The polyline of item i (metres, the tissue surface at z = 0), for the views.
  const std::vector<Eigen::Vector3d>& shape(std::size_t i) const { return shapes_[i]; }

 private:
  std::vector<knot::StitchKnotType> items_;
  std::vector<std::vector<Eigen::Vector3d>> shapes_;
};

}  // namespace microdex::station
