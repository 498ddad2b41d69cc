// microdex-bench state: the cost of the state hash against the cost of the step it follows,
// per scene. For each scene a novice simulated trainee drives the station's step
// (StepStation, as the haptic thread runs it) for --steps steps after a warm-up; after every
// step the state hash is taken and timed separately. Reported: median step and hash time, the
// state's size in bytes (what the hash reads), the ratio hash / step, and the hash's share of
// the haptic tick (1 / rate_hz) were it taken every tick (the station takes it once a second).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "common/state/state_hash.h"
#include "common/state/station_state_visit.h"
#include "station/sim_trainee.h"
#include "station/station_step.h"

namespace microdex::bench {
namespace {

struct ByteCount {
  template <typename T>
  void operator()(const char* /*name*/, const T* /*p*/, std::size_t n) {
    bytes += n * (std::is_same_v<T, bool> ? 1 : sizeof(T));
  }
  std::size_t bytes = 0;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double NowNs() {
  return static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::steady_clock::now().time_since_epoch())
                                 .count());
}

struct SceneResult {
  std::string scene;
  std::size_t state_bytes = 0;
  double step_median_ns = 0;
  double hash_median_ns = 0;
  double tick_ns = 0;
};

SceneResult Measure(const std::string& path, int steps, int scene_index, int scenes) {
  const scene::SceneModel scene = scene::LoadScene(path);
  station::Simulation sim(scene);
  state::StationState s = sim.MakeInitialState(1);
  station::SimTraineeDef def;
  def.skill = 0.0;
  station::SimTrainee trainee(scene, def);
  constexpr int kWarmUp = 500;
  std::vector<double> step_ns, hash_ns;
  step_ns.reserve(static_cast<std::size_t>(steps));
  hash_ns.reserve(static_cast<std::size_t>(steps));
  const bool tty = isatty(STDERR_FILENO) != 0;
  const double start = NowNs();
  std::uint64_t sink = 0;
  for (int k = 0; k < kWarmUp + steps; ++k) {
    const station::StationInput in{trainee.Read(s.step), {}};
    const double t0 = NowNs();
    station::StepStation(sim, in, s);
    const double t1 = NowNs();
    sink ^= state::CalcStateHash(s);
    const double t2 = NowNs();
    trainee.WriteForce(s.tool.f_T_W);
    if (k >= kWarmUp) {
      step_ns.push_back(t1 - t0);
      hash_ns.push_back(t2 - t1);
    }
    if (tty && k % 250 == 0) {
      const double done = static_cast<double>(k + 1) / (kWarmUp + steps);
      const double eta_s = (NowNs() - start) * 1e-9 * (1 / done - 1);
      std::fprintf(stderr, "\r[%d/%d] %s %3.0f %%, ETA %.0f s   ", scene_index + 1, scenes,
                   scene.name.c_str(), 100 * done, eta_s);
    }
  }
  if (tty) std::fprintf(stderr, "\r%*s\r", 70, "");
  SceneResult r;
  r.scene = path.substr(path.rfind('/') + 1);
  ByteCount count;
  state::VisitStationState(s, count);
  r.state_bytes = count.bytes;
  r.step_median_ns = Median(step_ns);
  r.hash_median_ns = Median(hash_ns);
  r.tick_ns = 1e9 / scene.haptic.rate_hz;
  if (sink == 42) std::fprintf(stderr, " ");  // keep the hashes
  return r;
}

int RunState(int argc, char** argv) {
  CLI::App app{"state hash cost against the station step, per scene"};
  std::string json_path;
  std::vector<std::string> scenes;
  int steps = 3000;
  app.add_option("--json", json_path, "write the results as JSON");
  app.add_option("--scene", scenes, "scene files (default: the station's shipped scenes)");
  app.add_option("--steps", steps, "timed steps per scene")->check(CLI::Range(10, 1000000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (scenes.empty()) {
    const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
    const std::string base = std::string(dir ? dir : MICRODEX_BENCH_SOURCE_DIR) + "/assets/scenes/";
    for (const char* f :
         {"needle_tube.yaml", "thread_pull.yaml", "tissue_press.yaml", "suture_on_tissue.yaml"}) {
      scenes.push_back(base + f);
    }
  }
  std::vector<SceneResult> results;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    try {
      results.push_back(
          Measure(scenes[i], steps, static_cast<int>(i), static_cast<int>(scenes.size())));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "microdex-bench state: %s\n", e.what());
      return 2;
    }
  }
  std::printf("%-24s %12s %14s %14s %12s %14s\n", "scene", "state bytes", "step median us",
              "hash median us", "hash/step", "hash/tick");
  for (const SceneResult& r : results) {
    const double ratio = r.hash_median_ns / r.step_median_ns;
    std::printf("%-24s %12zu %14.2f %14.2f %11.2f%% %13.2f%%\n", r.scene.c_str(), r.state_bytes,
                r.step_median_ns * 1e-3, r.hash_median_ns * 1e-3, 100 * ratio,
                100 * r.hash_median_ns / r.tick_ns);
  }
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench state: --json %s: cannot write\n", json_path.c_str());
      return 2;
    }
    f << "{\n  \"steps\": " << steps << ",\n  \"scenes\": [";
    for (std::size_t i = 0; i < results.size(); ++i) {
      const SceneResult& r = results[i];
      const double ratio = r.hash_median_ns / r.step_median_ns;
      f << (i ? ",\n" : "\n") << "    {\"scene\": \"" << r.scene
        << "\", \"state_bytes\": " << r.state_bytes << ", \"step_median_ns\": " << r.step_median_ns
        << ", \"hash_median_ns\": " << r.hash_median_ns << ", \"hash_per_step\": " << ratio
        << ", \"tick_ns\": " << r.tick_ns << ", \"hash_per_tick\": " << r.hash_median_ns / r.tick_ns
        << "}";
    }
    f << "\n  ]\n}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(state, "state", "state hash cost against the station step, per scene",
                        RunState);

}  // namespace microdex::bench
