#include "station/knot_quiz_module.h"

namespace microdex::station {

// The scene's loader has checked that the recogniser names each item's shape as its class.
KnotQuizModule::KnotQuizModule(const scene::SceneModel& scene) : items_(scene.knots->items) {
  for (std::size_t i = 0; i < items_.size(); ++i) shapes_.push_back(scene.knots->ItemShape(i));
}

void KnotQuizModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& /*f_T_W*/) {
  state::KnotQuizState& k = *s.knots;
  const std::uint32_t buttons = s.tool.buttons;
  const bool pressed = buttons != 0 && k.prev_buttons == 0;
  k.prev_buttons = buttons;
  const double now_s = static_cast<double>(in.step) * in.dt_s;
  if (!pressed || k.item >= static_cast<std::int32_t>(items_.size())) return;
  k.last_answer = static_cast<std::int32_t>(buttons);
  if (buttons == static_cast<std::uint32_t>(items_[static_cast<std::size_t>(k.item)])) {
    ++k.correct;
  }
  k.response_time_sum_s += now_s - k.item_start_s;
  ++k.item;
  k.item_start_s = now_s;
}

ModuleStatus KnotQuizModule::Status(const state::StationState& /*s*/) const { return {}; }

}  // namespace microdex::station
