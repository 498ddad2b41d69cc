// microdex-bench puncture: the needle-through-tissue physics (common/puncture), error against
// run time (common/puncture/README.md "Measured").
//
//   microdex-bench puncture [--json FILE] [--quick]
//
// nearest point: the analytic nearest needle point to a hole against sampling the arc with N
//   points (N = 16 … 4096), on random arcs and points: largest distance error against a dense
//   reference (10⁶ samples refined by the analytic answer) and median time per query, with the
//   ratio to the analytic query's time in the same run;
// pressing: the membrane's point stiffness at the puncture (threshold / indentation, the FEM
//   under the tip) at tissue levels 4 … 7 against the finest level 8 mesh, and the median and
//   p99 of StepPuncture while the tip presses (a new mesh every step);
// pass: a whole pass along the needle's circle at the stations' level 6: median and p99 step
//   time while pressing, while through the holes, and over all steps.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "bench_util.h"
#include "common/fem/tissue_model.h"
#include "tests/unit/puncture/puncture_scenarios.h"

namespace microdex::bench {
namespace {

using Clock = std::chrono::steady_clock;
using puncture::testing::ThroughScenario;

double ElapsedNs(Clock::time_point t0) {
  return std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
}

struct NearestRow {
  int samples = 0;  // 0: analytic
  double max_error_m = 0;
  double median_ns = 0;
  double ratio_to_analytic = 1;
};

double SampledNearest(const puncture::NeedleArc& arc, const Eigen::Vector3d& q, int n) {
  double best = 1e300;
  for (int i = 0; i <= n; ++i) best = std::min(best, (q - arc.Point(arc.sweep_rad * i / n)).norm());
  return best;
}

std::vector<NearestRow> MeasureNearest(int queries) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<puncture::NeedleArc> arcs(queries);
  std::vector<Eigen::Vector3d> points(queries);
  std::vector<double> reference(queries);
  const ThroughScenario sc;
  for (int i = 0; i < queries; ++i) {
    arcs[i] = sc.ArcWithTipAt(3.0 + 2.0 * u(rng));
    arcs[i].c_S += Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1e-3;
    points[i] = arcs[i].c_S + Eigen::Vector3d(u(rng), u(rng) * 0.3, u(rng)) * 6e-3;
    // The dense reference, never below the exact distance: the analytic answer wins where it is
    // nearer (as it must be, up to rounding).
    double d = 0;
    puncture::ClosestArcParameter(arcs[i], points[i], &d);
    reference[i] = std::min(d, SampledNearest(arcs[i], points[i], 1000000));
  }
  std::vector<NearestRow> rows;
  const Clock::time_point start = Clock::now();
  const int settings[] = {0, 16, 64, 256, 1024, 4096};
  int done = 0;
  for (const int n : settings) {
    NearestRow r;
    r.samples = n;
    std::vector<double> ns;
    ns.reserve(queries);
    double sink = 0;
    for (int i = 0; i < queries; ++i) {
      const Clock::time_point t0 = Clock::now();
      double d = 0;
      if (n == 0) {
        puncture::ClosestArcParameter(arcs[i], points[i], &d);
      } else {
        d = SampledNearest(arcs[i], points[i], n);
      }
      ns.push_back(ElapsedNs(t0));
      sink += d;
      r.max_error_m = std::max(r.max_error_m, std::abs(d - reference[i]));
    }
    r.median_ns = Percentile(ns, 0.5);
    if (sink == -1) std::printf("%g", sink);  // keeps the queries
    rows.push_back(r);
    Progress("nearest point", ++done, static_cast<int>(std::size(settings)), start);
  }
  for (NearestRow& r : rows) r.ratio_to_analytic = r.median_ns / rows.front().median_ns;
  return rows;
}

// The tip turned into the membrane until it punctures: the point stiffness at the puncture and
// the pressing steps' times.
struct PressRow {
  int level = 0;
  double stiffness_N_per_m = 0;
  double stiffness_error = 0;  // relative to the finest
  double median_us = 0, p99_us = 0;
  int steps = 0;
  double median_iterations = 0, median_unknowns = 0;
};

PressRow MeasurePress(int level, int max_level) {
  ThroughScenario sc;
  sc.tissue.level = level;
  sc.tissue.max_level = max_level;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  puncture::PunctureState st;
  PressRow r;
  r.level = level;
  std::vector<double> us, iterations, unknowns;
  // 2 mm/s at the tip: a careful approach.
  const double step_rad = 2e-6 / sc.radius_m;
  for (double a = sc.EntryAngle() - 0.02; st.punctures == 0 && a < sc.EntryAngle() + 0.8;
       a += step_rad) {
    const Clock::time_point t0 = Clock::now();
    puncture::StepPuncture(sc.def, model, sc.ArcWithTipAt(a), ws, tissue, st);
    if (st.pressing != 0) {
      us.push_back(ElapsedNs(t0) * 1e-3);
      iterations.push_back(ws.stats.iterations);
      unknowns.push_back(ws.stats.unknowns);
    }
  }
  r.median_iterations = Percentile(iterations, 0.5);
  r.median_unknowns = Percentile(unknowns, 0.5);
  r.steps = static_cast<int>(us.size());
  r.median_us = Percentile(us, 0.5);
  r.p99_us = Percentile(us, 0.99);
  r.stiffness_N_per_m = st.num_holes > 0 ? st.holes[0].normal_stiffness_N_per_m : 0.0;
  return r;
}

struct PassRow {
  double press_median_us = 0, press_p99_us = 0;
  double holes_median_us = 0, holes_p99_us = 0;
  double all_median_us = 0, all_p99_us = 0;
  int steps = 0, punctures = 0;
};

PassRow MeasurePass() {
  const ThroughScenario sc;
  const fem::TissueModel model = fem::BuildTissueModel(sc.tissue);
  fem::TissueWorkspace ws(model);
  fem::TissueState tissue = fem::MakeTissueState(model);
  puncture::PunctureState st;
  std::vector<double> press, holes, all;
  const double a0 = sc.EntryAngle() - 0.05, a1 = sc.ExitAngle() + 0.4;
  const int steps = static_cast<int>((a1 - a0) * sc.radius_m / 5e-6);  // 5 mm/s at 1 kHz
  for (int k = 0; k <= steps; ++k) {
    const Clock::time_point t0 = Clock::now();
    puncture::StepPuncture(sc.def, model, sc.ArcWithTipAt(a0 + (a1 - a0) * k / steps), ws, tissue,
                           st);
    const double t_us = ElapsedNs(t0) * 1e-3;
    all.push_back(t_us);
    (st.pressing != 0 ? press : holes).push_back(t_us);
  }
  PassRow r;
  r.steps = steps + 1;
  r.punctures = st.punctures;
  r.press_median_us = Percentile(press, 0.5);
  r.press_p99_us = Percentile(press, 0.99);
  r.holes_median_us = Percentile(holes, 0.5);
  r.holes_p99_us = Percentile(holes, 0.99);
  r.all_median_us = Percentile(all, 0.5);
  r.all_p99_us = Percentile(all, 0.99);
  return r;
}

int Run(int argc, char** argv) {
  CLI::App app{"microdex-bench puncture: needle through tissue, error against run time"};
  std::string json_path;
  bool quick = false;
  app.add_option("--json", json_path, "write the report as JSON to FILE");
  app.add_flag("--quick", quick, "fewer queries and levels (for tests)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const std::vector<NearestRow> nearest = MeasureNearest(quick ? 200 : 2000);
  std::printf("nearest point on the needle (%d random queries)\n", quick ? 200 : 2000);
  std::printf("%-10s %14s %12s %10s\n", "method", "max_error_m", "median_ns", "ratio");
  for (const NearestRow& r : nearest) {
    const std::string name = r.samples == 0 ? "analytic" : "N=" + std::to_string(r.samples);
    std::printf("%-10s %14.3g %12.1f %10.1f\n", name.c_str(), r.max_error_m, r.median_ns,
                r.ratio_to_analytic);
  }
  const int finest = quick ? 7 : 8;
  std::vector<int> levels = quick ? std::vector<int>{5, 6} : std::vector<int>{4, 5, 6, 7};
  std::vector<PressRow> press;
  const Clock::time_point start = Clock::now();
  const PressRow reference = MeasurePress(finest, finest);
  for (std::size_t i = 0; i < levels.size(); ++i) {
    press.push_back(MeasurePress(levels[i], finest));
    Progress("pressing", static_cast<int>(i + 1), static_cast<int>(levels.size()), start);
  }
  for (PressRow& r : press) {
    r.stiffness_error = std::abs(r.stiffness_N_per_m / reference.stiffness_N_per_m - 1.0);
  }
  std::printf(
      "\npressing until the puncture (reference: fine mesh, level %d: %.4g N/m, "
      "median %.0f us)\n",
      finest, reference.stiffness_N_per_m, reference.median_us);
  std::printf("%-6s %14s %12s %12s %10s %8s %10s %10s\n", "level", "stiffness_N/m", "rel_error",
              "median_us", "p99_us", "steps", "unknowns", "cg_iters");
  for (const PressRow& r : press) {
    std::printf("%-6d %14.4g %12.3g %12.1f %10.1f %8d %10.0f %10.0f\n", r.level,
                r.stiffness_N_per_m, r.stiffness_error, r.median_us, r.p99_us, r.steps,
                r.median_unknowns, r.median_iterations);
  }
  const PassRow pass = MeasurePass();
  std::printf("\na pass along the needle's circle at level 6 (%d steps, %d punctures)\n",
              pass.steps, pass.punctures);
  std::printf(
      "pressing: median %.1f us, p99 %.1f us; through the holes: median %.2f us, p99 "
      "%.2f us; all: median %.2f us, p99 %.1f us\n",
      pass.press_median_us, pass.press_p99_us, pass.holes_median_us, pass.holes_p99_us,
      pass.all_median_us, pass.all_p99_us);
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    if (!out) {
      std::fprintf(stderr, "microdex-bench puncture: cannot write %s\n", json_path.c_str());
      return 2;
    }
    out << "{\"nearest\": [";
    for (std::size_t i = 0; i < nearest.size(); ++i) {
      const NearestRow& r = nearest[i];
      out << (i ? ", " : "") << "{\"samples\": " << r.samples
          << ", \"max_error_m\": " << r.max_error_m << ", \"median_ns\": " << r.median_ns
          << ", \"ratio_to_analytic\": " << r.ratio_to_analytic << "}";
    }
    out << "], \"pressing\": {\"reference_level\": " << finest
        << ", \"reference_stiffness_N_per_m\": " << reference.stiffness_N_per_m << ", \"rows\": [";
    for (std::size_t i = 0; i < press.size(); ++i) {
      const PressRow& r = press[i];
      out << (i ? ", " : "") << "{\"level\": " << r.level
          << ", \"stiffness_N_per_m\": " << r.stiffness_N_per_m
          << ", \"stiffness_error\": " << r.stiffness_error << ", \"median_us\": " << r.median_us
          << ", \"p99_us\": " << r.p99_us << ", \"steps\": " << r.steps
          << ", \"median_unknowns\": " << r.median_unknowns
          << ", \"median_cg_iterations\": " << r.median_iterations << "}";
    }
    out << "]}, \"pass\": {\"steps\": " << pass.steps << ", \"punctures\": " << pass.punctures
        << ", \"press_median_us\": " << pass.press_median_us
        << ", \"press_p99_us\": " << pass.press_p99_us
        << ", \"holes_median_us\": " << pass.holes_median_us
        << ", \"holes_p99_us\": " << pass.holes_p99_us
        << ", \"all_median_us\": " << pass.all_median_us << ", \"all_p99_us\": " << pass.all_p99_us
        << "}}\n";
  }
  return 0;
}

MICRODEX_REGISTER_BENCH(puncture, "puncture",
                        "needle through tissue: nearest point vs sampling, pressing vs level", Run);

}  // namespace
}  // namespace microdex::bench
