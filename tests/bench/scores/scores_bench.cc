// microdex-bench scores: every training scene (a scene whose task is not follow_path) run to
// its end by the simulated trainee at skills 0.2, 0.5 and 0.9 with five seeds each, in
// simulated time. Reports each group's mean and standard deviation of the score, each module's
// step time, and whether the scene's scores tell the skills apart: means strictly ordered by
// skill, at least 8 points between neighbouring skills and 30 between 0.2 and 0.9, each
// group's standard deviation below a third of the 0.2-to-0.9 gap.
//
//   microdex-bench scores [--json FILE] [--scenes DIR] [--only NAME,...] [--seeds N]
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "common/base/json_text.h"
#include "common/scene/scene.h"
#include "station/scene_run.h"

namespace microdex::bench {
namespace {

// The training scenes, in the order of thesis §2.2 (those present in the folder are run).
constexpr const char* kTrainingScenes[] = {
    "tremor_hold",   "loop_along_wire", "needle_along_tube",     "grasp",     "nylon_loop",
    "knot_topology", "knot_placement",  "needle_through_tissue", "knot_tying"};

struct Group {
  std::string scene;
  double skill = 0;
  std::vector<double> scores;
  double mean = 0, sd = 0;
};

struct SceneSummary {
  std::string name;
  std::vector<Group> groups;
  std::vector<std::string> modules;
  std::vector<double> step_median_us, step_p99_us;
  bool separates = false;
  std::string why;
};

void Finish(Group& g) {
  const double n = static_cast<double>(g.scores.size());
  g.mean = std::accumulate(g.scores.begin(), g.scores.end(), 0.0) / n;
  double sq = 0;
  for (double s : g.scores) sq += (s - g.mean) * (s - g.mean);
  g.sd = g.scores.size() > 1 ? std::sqrt(sq / (n - 1)) : 0.0;
}

// The separation criteria of the report's header; why is empty when they hold.
std::string CheckSeparation(const std::vector<Group>& g) {
  std::ostringstream why;
  for (std::size_t i = 1; i < g.size(); ++i) {
    if (!(g[i].mean - g[i - 1].mean >= 8)) {
      why << "skills " << g[i - 1].skill << " and " << g[i].skill << " only "
          << g[i].mean - g[i - 1].mean << " points apart; ";
    }
  }
  const double gap = g.back().mean - g.front().mean;
  if (!(gap >= 30)) why << "0.2 to 0.9 only " << gap << " points; ";
  for (const Group& x : g) {
    if (!(x.sd < gap / 3)) why << "sd " << x.sd << " at skill " << x.skill << " >= gap / 3; ";
  }
  return why.str();
}

using ::microdex::JsonNumber;

int Run(int argc, char** argv) {
  std::string json_path;
  // The repository's scenes: from MICRODEX_SOURCE_DIR (the tests set it), else the working
  // directory (the repository root).
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  std::string scenes_dir = std::string(root != nullptr ? root : ".") + "/assets/scenes";
  std::vector<std::string> only;
  int seeds = 5;
  CLI::App app{"microdex-bench scores: do the training scenes' scores tell skills apart?"};
  app.add_option("--json", json_path, "write the report as JSON");
  app.add_option("--scenes", scenes_dir, "folder of scene files");
  app.add_option("--only", only, "scene names (file stems), comma-separated")->delimiter(',');
  app.add_option("--seeds", seeds, "seeds per skill")->check(CLI::Range(1, 100));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  std::vector<scene::SceneModel> scenes;
  std::vector<std::string> names;
  for (const char* stem : kTrainingScenes) {
    if (!only.empty() && std::find(only.begin(), only.end(), stem) == only.end()) continue;
    const std::filesystem::path file =
        std::filesystem::path(scenes_dir) / (std::string(stem) + ".yaml");
    if (!std::filesystem::exists(file)) continue;
    try {
      scenes.push_back(scene::LoadScene(file.string()));
      names.push_back(stem);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "microdex-bench scores: %s\n", e.what());
      return 2;
    }
  }
  if (scenes.empty()) {
    std::fprintf(stderr, "microdex-bench scores: no training scene in %s\n", scenes_dir.c_str());
    return 2;
  }
  const double skills[] = {0.2, 0.5, 0.9};
  const int total = static_cast<int>(scenes.size()) * 3 * seeds;
  int done = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const bool tty = isatty(STDERR_FILENO) != 0;
  std::vector<SceneSummary> out;
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    SceneSummary sum;
    sum.name = names[k];
    std::vector<std::vector<double>> medians, p99s;
    for (double skill : skills) {
      Group g;
      g.scene = names[k];
      g.skill = skill;
      for (int seed = 1; seed <= seeds; ++seed) {
        station::SimTraineeDef def;
        def.skill = skill;
        def.seed = static_cast<std::uint64_t>(seed);
        const station::SceneRunResult r =
            station::RunSceneWithTrainee(scenes[k], def, static_cast<std::uint64_t>(seed));
        g.scores.push_back(r.score.score);
        sum.modules = r.modules;
        medians.push_back(r.step_time_median_s);
        p99s.push_back(r.step_time_p99_s);
        ++done;
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::fprintf(stderr, "%s[%d/%d, ETA %.0f s] %s skill %.1f seed %d: %.1f%s", tty ? "\r" : "",
                     done, total, elapsed / done * (total - done), names[k].c_str(), skill, seed,
                     r.score.score, tty ? "   " : "\n");
      }
      Finish(g);
      sum.groups.push_back(g);
    }
    for (std::size_t m = 0; m < sum.modules.size(); ++m) {
      std::vector<double> a, b;
      for (const auto& v : medians) a.push_back(v[m]);
      for (const auto& v : p99s) b.push_back(v[m]);
      std::sort(a.begin(), a.end());
      sum.step_median_us.push_back(a[a.size() / 2] * 1e6);
      sum.step_p99_us.push_back(*std::max_element(b.begin(), b.end()) * 1e6);
    }
    sum.why = CheckSeparation(sum.groups);
    sum.separates = sum.why.empty();
    out.push_back(sum);
  }
  if (tty) std::fprintf(stderr, "\n");
  std::printf("%-24s %6s %8s %7s   %s\n", "scene", "skill", "mean", "sd", "separates");
  bool all = true;
  for (const SceneSummary& s : out) {
    for (const Group& g : s.groups) {
      std::printf("%-24s %6.1f %8.1f %7.1f   %s\n", s.name.c_str(), g.skill, g.mean, g.sd,
                  g.skill == skills[2] ? (s.separates ? "yes" : ("NO: " + s.why).c_str()) : "");
    }
    all = all && s.separates;
  }
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench scores: %s: cannot write\n", json_path.c_str());
      return 2;
    }
    f << "{\"seeds\": " << seeds << ", \"scenes\": [";
    bool first = true;
    for (const SceneSummary& s : out) {
      for (const Group& g : s.groups) {
        f << (first ? "\n  " : ",\n  ") << "{\"scene\": \"" << g.scene
          << "\", \"skill\": " << JsonNumber(g.skill) << ", \"n\": " << g.scores.size()
          << ", \"mean\": " << JsonNumber(g.mean) << ", \"sd\": " << JsonNumber(g.sd) << "}";
        first = false;
      }
    }
    f << "\n], \"separation\": [";
    for (std::size_t i = 0; i < out.size(); ++i) {
      const SceneSummary& s = out[i];
      f << (i ? ",\n  " : "\n  ") << "{\"scene\": \"" << s.name
        << "\", \"separates\": " << (s.separates ? "true" : "false") << ", \"modules\": [";
      for (std::size_t m = 0; m < s.modules.size(); ++m) {
        f << (m ? ", " : "") << "{\"name\": \"" << s.modules[m]
          << "\", \"step_median_us\": " << JsonNumber(s.step_median_us[m])
          << ", \"step_p99_us\": " << JsonNumber(s.step_p99_us[m]) << "}";
      }
      f << "]}";
    }
    f << "\n]}\n";
  }
  return all ? 0 : 1;
}

}  // namespace

MICRODEX_REGISTER_BENCH(scores, "scores",
                        "training scenes at skills 0.2/0.5/0.9: do the scores tell skills apart?",
                        Run);

}  // namespace microdex::bench
