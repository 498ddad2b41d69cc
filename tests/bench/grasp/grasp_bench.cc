// microdex-bench grasp: error of the grasp physics (common/grasp) against analytic values, as a
// function of the contact solver's iterations and sub-steps, with the median step time of each
// setting (common/grasp/README.md "Measured").
//
//   microdex-bench grasp [--json FILE] [--quick] [--iterations N...] [--substeps N...]
//
// Per setting: the hold threshold of a two-jaw grasp on a 1 mg cube found by bisection against
// m g / (2 mu); the sliding acceleration of a box on a 35° incline against
// g (sin θ - mu cos θ); the rotation an aligned lift induces (0 exactly); the median wall time of
// StepGrasp over the lifts.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "tests/unit/grasp/grasp_scenarios.h"

namespace microdex::bench {
namespace {

using Clock = std::chrono::steady_clock;
namespace gt = grasp::testing;

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Row {
  int iterations = 0;
  int substeps = 0;
  double hold_threshold_N = 0.0;
  double hold_exact_N = 0.0;
  double hold_error = 0.0;  // relative
  double slide_m_per_s2 = 0.0;
  double slide_exact_m_per_s2 = 0.0;
  double slide_error = 0.0;  // relative
  double stick_creep_m = 0.0;
  double aligned_rotation_rad = 0.0;
  double step_median_us = 0.0;
};

constexpr double kMu = 0.5;
constexpr double kG = 9.81;

Row Measure(int iterations, int substeps, int bisections, std::vector<double>& step_us) {
  Row r;
  r.iterations = iterations;
  r.substeps = substeps;
  grasp::GraspDef def = gt::MilligramCubeDef(kMu);
  def.solver.iterations = iterations;
  def.solver.substeps = substeps;
  // Hold threshold; the cube's mass from its size and density, not from the model.
  const gt::HoldThreshold t = gt::FindHoldThreshold(def, 1e-3, bisections);
  r.hold_threshold_N = t.threshold_N();
  r.hold_exact_N = def.density_kg_per_m3 * 1e-9 * kG / (2.0 * kMu);
  r.hold_error = std::abs(r.hold_threshold_N / r.hold_exact_N - 1.0);
  // Sliding and sticking on an incline (a flat box, which does not tip).
  grasp::GraspDef flat = def;
  flat.shape.box_size_m.z() = 0.25e-3;
  flat.table_friction = kMu;
  const double theta = 35.0 * std::numbers::pi / 180.0;
  const gt::InclineResult slide = gt::RunIncline(flat, theta, 0.05, 0.2);
  r.slide_m_per_s2 = slide.acceleration_m_per_s2;
  r.slide_exact_m_per_s2 = kG * (std::sin(theta) - kMu * std::cos(theta));
  r.slide_error = std::abs(r.slide_m_per_s2 / r.slide_exact_m_per_s2 - 1.0);
  const gt::InclineResult stick = gt::RunIncline(flat, 0.9 * std::atan(kMu), 0.5, 1.5);
  r.stick_creep_m = std::abs(stick.displacement_m);
  // An aligned lift, timed step by step.
  gt::LiftOptions o;
  o.squeeze_m = 40e-6;
  step_us.clear();
  const gt::LiftResult lift = gt::RunLift(def, 1e-3, o, &step_us);
  r.aligned_rotation_rad = lift.final.metrics.max_induced_rotation_rad;
  r.step_median_us = Median(step_us);
  return r;
}

int RunGrasp(int argc, char** argv) {
  CLI::App app{"grasp: error against analytic values vs the solver's iterations and sub-steps"};
  std::string json_path;
  bool quick = false;
  std::vector<int> iterations = {5, 10, 20, 40, 80};
  std::vector<int> substeps = {1, 2, 4};
  app.add_option("--json", json_path, "write the results as JSON");
  app.add_flag("--quick", quick, "fewer settings and a coarser bisection (CTest)");
  app.add_option("--iterations", iterations, "solver iterations to measure")
      ->check(CLI::Range(1, 1000));
  app.add_option("--substeps", substeps, "sub-steps to measure")->check(CLI::Range(1, 100));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (quick) {
    iterations = {5, 20};
    substeps = {1};
  }
  const int bisections = quick ? 8 : 14;
  const bool tty = isatty(STDERR_FILENO) != 0;
  const int total = static_cast<int>(iterations.size() * substeps.size());
  std::vector<Row> rows;
  std::vector<double> step_us;
  const auto start = Clock::now();
  for (int s : substeps) {
    for (int it : iterations) {
      if (tty) {
        const int done = static_cast<int>(rows.size());
        const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        const double eta = done > 0 ? elapsed * (total - done) / done : 0.0;
        std::fprintf(stderr, "\r[%d/%d] iterations %d, substeps %d, ETA %.0f s   ", done + 1, total,
                     it, s, eta);
      }
      rows.push_back(Measure(it, s, bisections, step_us));
    }
  }
  if (tty) std::fprintf(stderr, "\r%*s\r", 70, "");
  std::printf("%10s %8s %12s %10s %12s %10s %12s %12s %10s\n", "iterations", "substeps",
              "hold [uN]", "hold err", "slide[m/s2]", "slide err", "creep [nm]", "turn [mrad]",
              "step [us]");
  for (const Row& r : rows) {
    std::printf("%10d %8d %12.4f %9.2f%% %12.4f %9.2f%% %12.3f %12.3f %10.2f\n", r.iterations,
                r.substeps, r.hold_threshold_N * 1e6, 100 * r.hold_error, r.slide_m_per_s2,
                100 * r.slide_error, r.stick_creep_m * 1e9, r.aligned_rotation_rad * 1e3,
                r.step_median_us);
  }
  std::printf(
      "(1 mg cube, mu %.1f: hold threshold exact m g / (2 mu) = %.4f uN; incline 35°, exact "
      "g (sin - mu cos) = %.4f m/s^2; creep: a sticking box over 1 s at 0.9 atan(mu); turn: "
      "rotation of an aligned lift; step: median StepGrasp wall time during the lift)\n",
      kMu, rows.empty() ? 0.0 : rows[0].hold_exact_N * 1e6,
      rows.empty() ? 0.0 : rows[0].slide_exact_m_per_s2);
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench grasp: --json %s: cannot write\n", json_path.c_str());
      return 2;
    }
    f << "{\n  \"study\": \"grasp\",\n  \"mu\": " << kMu << ",\n  \"settings\": [";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      f << (i ? ",\n" : "\n") << "    {\"iterations\": " << r.iterations
        << ", \"substeps\": " << r.substeps << ", \"hold_threshold_N\": " << r.hold_threshold_N
        << ", \"hold_exact_N\": " << r.hold_exact_N << ", \"hold_error\": " << r.hold_error
        << ", \"slide_m_per_s2\": " << r.slide_m_per_s2
        << ", \"slide_exact_m_per_s2\": " << r.slide_exact_m_per_s2
        << ", \"slide_error\": " << r.slide_error << ", \"stick_creep_m\": " << r.stick_creep_m
        << ", \"aligned_rotation_rad\": " << r.aligned_rotation_rad
        << ", \"step_median_us\": " << r.step_median_us << "}";
    }
    f << "\n  ]\n}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(grasp, "grasp",
                        "grasp physics: error vs solver iterations and sub-steps, step time",
                        RunGrasp);

}  // namespace microdex::bench
