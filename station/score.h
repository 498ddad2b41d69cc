#pragma once
// The task score of a needle-in-tube run, from the running totals the haptic thread keeps
// (state::ScoreState). Simple and explainable:
//   contact fraction  c = time in contact / time
//   clearance factor  g = clamp(mean clearance / tube radius, 0, 1)
//   score             = 100 (1 − c) (1 + g) / 2
// so a run that never touches and keeps the needle on the core circle scores 100, one that
// never touches but rides the wall 50, and time in contact takes its share off.
// Scenes without the needle module (thread, tissue): "contact" is any module's fault (thread
// overstretched, tissue pressed too hard) and score = 100 (1 − c).

#include "common/net/messages.h"
#include "common/scene/scene.h"
#include "common/state/station_state.h"

namespace microdex::station {

net::Score CalcScore(const scene::SceneModel& scene, const state::ScoreState& totals);

}  // namespace microdex::station
