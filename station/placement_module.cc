#include "station/placement_module.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace microdex::station {

PlacementErrors CalcPlacementErrors(const scene::PlacementSceneDef& def,
                                    const state::PlacementState& p) {
  PlacementErrors e;
  const int placed = std::min(p.count, state::kMaxStitches);
  const double ideal_rad = 2 * std::numbers::pi / def.stitches;
  // Gaps between neighbours, sorted by azimuth; stitches not placed leave their gap missing,
  // which counts as a whole gap's error each.
  std::array<double, state::kMaxStitches> sorted{};
  std::copy_n(p.azimuth_rad.begin(), placed, sorted.begin());
  std::sort(sorted.begin(), sorted.begin() + placed);
  double sq = 0;
  for (int i = 0; i < placed; ++i) {
    const double next = i + 1 < placed ? sorted[i + 1] : sorted[0] + 2 * std::numbers::pi;
    const double gap = placed > 1 ? next - sorted[i] : 2 * std::numbers::pi;
    sq += (gap - ideal_rad) * (gap - ideal_rad);
  }
  sq += static_cast<double>(std::max(def.stitches - placed, 0)) * ideal_rad * ideal_rad;
  e.spacing_rms_rad = std::sqrt(sq / def.stitches);
  double bite_sq = 0;
  for (int i = 0; i < placed; ++i) bite_sq += std::pow(p.bite_m[i] - def.bite_m, 2);
  e.bite_rms_m = placed > 0 ? std::sqrt(bite_sq / placed) : def.bite_m;
  return e;
}

PlacementModule::PlacementModule(const scene::SceneModel& scene) : def_(*scene.placement) {}

void PlacementModule::Step(const ToolInput& in, state::StationState& s,
                           Eigen::Vector3d& /*f_T_W*/) {
  state::PlacementState& p = *s.placement;
  const std::uint32_t buttons = s.tool.buttons;
  const bool pressed = buttons != 0 && p.prev_buttons == 0;
  p.prev_buttons = buttons;
  if (!pressed || p.count >= std::min(def_.stitches, state::kMaxStitches)) return;
  const Eigen::Vector3d& tip = in.X_WT.translation();
  double azimuth = std::atan2(tip.y(), tip.x());
  if (azimuth < 0) azimuth += 2 * std::numbers::pi;
  p.azimuth_rad[static_cast<std::size_t>(p.count)] = azimuth;
  p.bite_m[static_cast<std::size_t>(p.count)] = def_.end_height_m - tip.z();
  ++p.count;
}

}  // namespace microdex::station
