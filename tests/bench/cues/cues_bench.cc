// microdex-bench cues: the predictive cue on scripted reaches (tests/support/reach_scripts.h):
// seeded minimum-jerk reaches of 3–8 mm in 0.6–1.2 s with 5–15 µm of 8–12 Hz tremor and 2 µm
// of sensor noise, half of them ending 1.5–4 × the warning limit beside their target, the
// others within 0.5 × the limit. Reported: the median lead of the first warning over the end of
// an erring reach (the error), the share of erring reaches warned >= 150 ms ahead (hit rate),
// the share of correct reaches warned at all (false alarms); goals: hit rate >= 0.8, false
// alarms <= 0.1. Also the predictor's cost per step.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench_registry.h"
#include "common/base/json_text.h"
#include "common/cues/end_point_predictor.h"
#include "tests/support/reach_scripts.h"

namespace microdex::bench {
namespace {

std::string Num(double v) { return JsonNumber(v, 6); }

// Median ns per predictor step over the samples of the first reaches.
double StepCostNs(const testing::ReachSetDef& def) {
  const cues::EndPointPredictorModel model = cues::MakeEndPointPredictor({});
  const std::vector<testing::Reach> reaches = testing::MakeReaches(def);
  std::vector<double> per_step;
  for (std::size_t k = 0; k < std::min<std::size_t>(reaches.size(), 20); ++k) {
    int start = 0;
    const auto p = testing::SampleReach(def, reaches[k], 0.4, k, &start);
    cues::EndPointPredictorState s;
    const auto t0 = std::chrono::steady_clock::now();
    double sink = 0;
    for (const Eigen::Vector3d& x : p) {
      const cues::EndPointPrediction e = cues::StepEndPointPredictor(model, x, s);
      sink += e.tau;
      cues::StepPredictiveWarning(e, 0.0, def.limit_m, 1e-3, s);
    }
    const auto t1 = std::chrono::steady_clock::now();
    if (sink == -1) std::fprintf(stderr, " ");
    per_step.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() /
                       static_cast<double>(p.size()));
  }
  std::sort(per_step.begin(), per_step.end());
  return per_step[per_step.size() / 2];
}

int RunCues(int argc, char** argv) {
  CLI::App app{"the predictive cue on scripted reaches: lead, hit rate, false alarms"};
  std::string json_path;
  testing::ReachSetDef def;
  int seeds = 3;
  app.add_option("--json", json_path, "write the results as JSON");
  app.add_option("--reaches", def.reaches, "reaches per seed")->check(CLI::Range(10, 100000));
  app.add_option("--seeds", seeds, "seeds 1..N")->check(CLI::Range(1, 100));
  app.add_option("--limit", def.limit_m, "warning limit, m")->check(CLI::Range(1e-5, 0.05));
  app.add_option("--err-min", def.err_min, "erring reaches miss by at least this × the limit")
      ->check(CLI::Range(1.0, 100.0));
  app.add_option("--ok-max", def.ok_max, "correct reaches miss by at most this × the limit")
      ->check(CLI::Range(0.0, 1.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  testing::PredictiveReport all;
  std::vector<double> leads;
  for (int seed = 1; seed <= seeds; ++seed) {
    def.seed = static_cast<std::uint64_t>(seed);
    const testing::PredictiveReport r = testing::EvaluatePredictive(def);
    all.erring += r.erring;
    all.correct += r.correct;
    all.hits += r.hits;
    all.warned_erring += r.warned_erring;
    all.false_alarms += r.false_alarms;
    leads.insert(leads.end(), r.lead_ms.begin(), r.lead_ms.end());
  }
  std::sort(leads.begin(), leads.end());
  const double lead_median = leads.empty() ? NAN : leads[leads.size() / 2];
  const double lead_p10 = leads.empty() ? NAN : leads[leads.size() / 10];
  const double hit_rate = all.erring ? static_cast<double>(all.hits) / all.erring : 0.0;
  const double fa_rate = all.correct ? static_cast<double>(all.false_alarms) / all.correct : 0.0;
  const double cost_ns = StepCostNs(def);
  std::printf("predictive: %d erring reaches, %d correct (seeds 1..%d, limit %.3g mm)\n",
              all.erring, all.correct, seeds, def.limit_m * 1e3);
  std::printf(
      "  lead median %.0f ms (p10 %.0f ms), hit rate %.3f (goal >= 0.8), false alarms "
      "%.3f (goal <= 0.1), predictor %.0f ns/step\n",
      lead_median, lead_p10, hit_rate, fa_rate, cost_ns);
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench cues: --json '%s': cannot write\n", json_path.c_str());
      return 2;
    }
    f << "{\n  \"predictive\": {\"lead_ms_median\": " << Num(lead_median)
      << ", \"lead_ms_p10\": " << Num(lead_p10) << ", \"hit_rate\": " << Num(hit_rate)
      << ", \"false_alarm_rate\": " << Num(fa_rate) << ", \"erring\": " << all.erring
      << ", \"correct\": " << all.correct << ", \"limit_m\": " << Num(def.limit_m)
      << ", \"err_min\": " << Num(def.err_min) << ", \"ok_max\": " << Num(def.ok_max)
      << ", \"seeds\": " << seeds << ", \"step_ns_median\": " << Num(cost_ns)
      << ", \"goals\": {\"lead_ms\": 150, \"hit_rate\": 0.8, \"false_alarm_rate\": 0.1}}\n}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(cues, "cues",
                        "the predictive cue on scripted reaches: lead, hit rate, false alarms",
                        RunCues);

}  // namespace microdex::bench
