#pragma once
// A scene run to its end by the simulated trainee, in simulated time and without a haptic
// loop or DDS: the same steps as a station's (StepStation after the trainee's sample, the force
// back to the trainee), for score reports and tests. A station run with --unpaced gives the
// same states step for step.

#include <cstdint>
#include <string>
#include <vector>

#include "common/net/messages.h"
#include "common/scene/scene.h"
#include "station/sim_trainee.h"

namespace microdex::station {

struct SceneRunResult {
  net::Score score;  // at the task's end (or max_duration_s)
  std::uint64_t steps = 0;
  std::vector<std::string> modules;
  std::vector<double> step_time_median_s;  // per module, wall time
  std::vector<double> step_time_p99_s;
};

// Runs until the scene's task ends, or max_duration_s of simulated time (0: the scene's time
// limit). Throws std::runtime_error for a scene whose modules this build lacks.
SceneRunResult RunSceneWithTrainee(const scene::SceneModel& scene, const SimTraineeDef& trainee,
                                   std::uint64_t seed, double max_duration_s = 0);

}  // namespace microdex::station
