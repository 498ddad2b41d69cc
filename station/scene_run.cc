#include "station/scene_run.h"

#include <algorithm>
#include <cmath>

#include "station/rt/clock.h"
#include "station/score.h"
#include "station/station_step.h"

namespace microdex::station {
namespace {

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

}  // namespace

SceneRunResult RunSceneWithTrainee(const scene::SceneModel& scene, const SimTraineeDef& trainee,
                                   std::uint64_t seed, double max_duration_s) {
  Simulation sim(scene);
  rt::MonotonicClock clock;
  sim.set_step_clock(&clock);
  SimTrainee device(scene, trainee);
  SimTraineeDef other_hand = trainee;
  other_hand.hand = 1;
  SimTrainee second(scene, other_hand);  // read only in bimanual scenes
  state::StationState state = sim.MakeInitialState(seed);
  const double duration_s = max_duration_s > 0 ? max_duration_s : scene.task.time_limit_s;
  const auto max_steps = static_cast<std::uint64_t>(std::llround(duration_s / sim.dt_s()));
  std::vector<std::vector<double>> times(sim.module_count());
  for (auto& t : times) t.reserve(max_steps);
  while (state.step < max_steps && state.score.outcome == 0) {
    StationInput in;
    in.device = device.Read(state.step);
    CanonicalizeDeviceSample(in.device);
    if (state.second_tool) {
      in.second = second.Read(state.step);
      CanonicalizeDeviceSample(in.second);
    }
    StepStation(sim, in, state);
    device.WriteWrench(state.tool.f_T_W, state.tool.tau_T_W);
    if (state.second_tool) second.WriteWrench(state.second_tool->f_T_W, state.second_tool->tau_T_W);
    for (std::size_t i = 0; i < sim.module_count(); ++i)
      times[i].push_back(sim.last_step_time_s(i));
  }
  if (scene.knot_tying && state.thread) {
    const Eigen::Matrix3Xd& x = state.thread->thread.x_W;
    std::vector<Eigen::Vector3d> nodes(static_cast<std::size_t>(x.cols()));
    for (Eigen::Index i = 0; i < x.cols(); ++i) nodes[static_cast<std::size_t>(i)] = x.col(i);
    state.score.tied_knot = static_cast<std::int32_t>(RecogniseTiedKnot(scene, nodes));
  }
  SceneRunResult r;
  r.score = CalcScore(scene, state.score);
  r.score.is_final = true;
  r.steps = state.step;
  for (std::size_t i = 0; i < sim.module_count(); ++i) {
    r.modules.push_back(sim.module(i).name());
    r.step_time_median_s.push_back(Quantile(times[i], 0.5));
    r.step_time_p99_s.push_back(Quantile(times[i], 0.99));
  }
  return r;
}

}  // namespace microdex::station
