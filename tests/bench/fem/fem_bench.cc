// microdex-bench fem: the accuracy and speed study of thesis §3.3 (figures 3.5–3.8).
// A 20 × 20 cm domain, G = 1 N/cm², a 10 cm bar pressed down 1 cm; G1 bar at the centre, G2
// bar near the border (y = 2.5 cm), G3 a bar through the centre at 30° (timing only).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "common/base/json_text.h"
#include "common/fem/navier.h"
#include "common/fem/tissue_step.h"
#include "tests/bench/fem/fem_contact_report.h"
#include "tests/bench/fem/fem_two_level_probe.h"

namespace microdex::fem {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDomain_m = 20 * kMetrePerCm;
constexpr double kPress_m = 1 * kMetrePerCm;
constexpr double kBarLength_m = 10 * kMetrePerCm;

struct Case {
  const char* name;
  double cx_m, cy_m, angle_rad;
  bool has_navier;
};

const Case kCases[] = {
    {"G1", 0.10, 0.10, 0.0, true},
    {"G2", 0.10, 0.025, 0.0, true},
    {"G3", 0.10, 0.10, std::numbers::pi / 6, false},
};

ToolContact BarTool(const Case& c, double depth_m, double shift_x_m = 0, double shift_y_m = 0) {
  const double dx = 0.5 * kBarLength_m * std::cos(c.angle_rad);
  const double dy = 0.5 * kBarLength_m * std::sin(c.angle_rad);
  return MakeBarTool({c.cx_m + shift_x_m - dx, c.cy_m + shift_y_m - dy, -depth_m},
                     {c.cx_m + shift_x_m + dx, c.cy_m + shift_y_m + dy, -depth_m});
}

// The multi-scale mesh of level l: cells touching the bar at level l, end zones down to
// cells of bar length / end_resolution (level 7 for the 10 cm bar); its grid reaches that.
TissueDef StudyDef(int level, MeshKind mesh, SolverKind solver, double grading,
                   double end_resolution) {
  TissueDef def;
  def.length_x_m = kDomain_m;
  def.length_y_m = kDomain_m;
  def.shear_modulus_Pa = 1 * kPascalPerNewtonPerCm2;
  def.thickness_m = 1 * kMetrePerCm;
  def.end_resolution = end_resolution;
  def.max_level = mesh == MeshKind::kMultiscale ? std::max(level, 8) : level;
  def.level = level;
  def.mesh = mesh;
  def.solver = solver;
  def.grading = grading;
  def.cg_max_iterations = 100000;
  return def;
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<size_t>(std::lround(p * static_cast<double>(v.size() - 1))))];
}

double ThreadCpuMicroseconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
}

struct Run {
  std::string case_name, mesh, solver;
  int level = 0, unknowns = 0, contacts = 0, iterations = 0, steps = 0;
  double step_us = kNaN, cached_step_us = kNaN, select_us = kNaN, assemble_us = kNaN,
         solve_us = kNaN, forces_us = kNaN;
  double rms = kNaN, nodal_rms = kNaN, force_error = kNaN, force_N = kNaN, residual = kNaN;
  std::string status;
};

struct Distribution {
  std::string case_name, mesh;
  int level;
  std::vector<double> x_m, f_N, ref_N;
};

struct Moving {
  int level;
  std::string solver, ordering, constraint;
  bool attached;  // TissueDef::attached_mesh
  double median_us, p99_us, max_us, reuse_fraction;
  int failed, steps;
  double mean_unknowns;
  double select_us, assemble_us, solve_us;  // medians of the moving steps' stages
  // The step's CPU time (this thread): what the step costs when the shared machine preempts it.
  double cpu_median_us, cpu_p99_us;
  double static_median_us;  // same model, tool held still, same run
  double iterations;        // median (P)CG iterations of the moving steps
  double twisted_fraction;  // steps whose attached mesh was twisted (the tool's turn absorbed)
  int reattached;           // steps that attached the mesh afresh
};

struct Options {
  std::string json, plot_dir;
  int max_level = 8;
  int min_steps = 15;
  // A run also lasts at least min_time_s: 15 steps of a fast mesh are 10 ms, short enough for
  // one burst of a shared host's noise to move their median (and with it the same-run ratio
  // against the fine mesh); 0.25 s is hundreds of steps.
  double min_time_s = 0.25;
  double budget_s = 0.4;
  double grading = 2.0;
  double end_resolution = TissueDef{}.end_resolution;
  bool moving_only = false;  // only the moving-tool rows of the stations' solver (iterating)
  bool two_level_probe = false;
};

// Times steps of a bar whose depth oscillates ±10 % around 1 cm (the selection and the
// pattern stay, the right-hand side changes), re-assembling values every step.
void TimeRun(const TissueModel& model, const Case& c, bool reuse_values, const Options& opt,
             Run& run) {
  TissueWorkspace ws(model);
  TissueState state = MakeTissueState(model);
  ws.reuse_values = reuse_values;
  std::vector<double> total, select, assemble, solve, forces, iterations;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0;; ++k) {
    const double depth = kPress_m * (1 + 0.1 * std::sin(2 * std::numbers::pi * k / 16));
    StepTissue(model, BarTool(c, depth), ws, state);
    if (k < 2) continue;  // warm-up: first analysis, first warm start
    total.push_back(ws.stats.total_us);
    select.push_back(ws.stats.select_us);
    assemble.push_back(ws.stats.assemble_us);
    solve.push_back(ws.stats.solve_us);
    forces.push_back(ws.stats.forces_us);
    iterations.push_back(ws.stats.iterations);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if ((static_cast<int>(total.size()) >= opt.min_steps && elapsed >= opt.min_time_s) ||
        (elapsed > opt.budget_s && total.size() >= 3))
      break;
  }
  if (reuse_values) {
    run.cached_step_us = Median(total);
    return;
  }
  run.step_us = Median(total);
  run.select_us = Median(select);
  run.assemble_us = Median(assemble);
  run.solve_us = Median(solve);
  run.forces_us = Median(forces);
  run.iterations = static_cast<int>(Median(iterations));
  run.steps = static_cast<int>(total.size());
}

int RunFem(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + ": expected a value");
      return argv[++i];
    };
    if (a == "--json") {
      opt.json = value();
    } else if (a == "--plot") {
      opt.plot_dir = value();
    } else if (a == "--quick") {
      opt.max_level = 5;
      opt.min_steps = 5;
      opt.min_time_s = 0;
      opt.budget_s = 0.05;
    } else if (a == "--max-level") {
      opt.max_level = std::stoi(value());
      if (opt.max_level < 1 || opt.max_level > 8)
        throw std::invalid_argument("--max-level: expected 1..8");
    } else if (a == "--moving-only") {
      opt.moving_only = true;
    } else if (a == "--two-level-probe") {
      opt.two_level_probe = true;
    } else if (a == "--continuity-probe") {
      return RunContinuityProbe();
    } else if (a == "--grading") {
      opt.grading = std::stod(value());
    } else if (a == "--end-resolution") {
      opt.end_resolution = std::stod(value());
      if (!(opt.end_resolution >= 0 && opt.end_resolution <= 1e4))
        throw std::invalid_argument("--end-resolution: expected 0 (off) to 1e4");
    } else if (a == "--help" || a == "-h") {
      std::printf(
          "microdex-bench fem [--json FILE] [--plot DIR] [--quick] [--max-level N] "
          "[--grading G] [--end-resolution R] [--moving-only] [--two-level-probe] "
          "[--continuity-probe]\n"
          "  the thesis §3.3 study: force along the bar, RMS error and CPU time by level,\n"
          "  fine vs multi-scale mesh, solvers cg, pcg_jacobi, pcg_ic, pcg_dic, cholmod\n"
          "  --moving-only: only the moving-tool rows of pcg_jacobi, pcg_ic and pcg_dic\n"
          "  --two-level-probe: PCG iterations of IC(0) against two-level preconditioners\n"
          "  --continuity-probe: step changes of the continuity motions, same / changed mesh\n");
      return 0;
    } else {
      throw std::invalid_argument("unknown option '" + a + "'");
    }
  }
  if (opt.two_level_probe) {  // the moving bar's first 40 poses at level 7
    TissueDef def =
        StudyDef(7, MeshKind::kMultiscale, SolverKind::kPcgIc, opt.grading, opt.end_resolution);
    const TissueModel model = BuildTissueModel(def);
    std::vector<ToolContact> tools;
    for (int k = 0; k < 40; ++k) {
      const double t = 1e-3 * k;
      const double cx = 0.06 + 0.08 * (0.5 - 0.5 * std::cos(2 * std::numbers::pi * t / 0.16));
      tools.push_back(
          BarTool(Case{"moving", cx, 0.10 + 0.03 * std::sin(2 * std::numbers::pi * t / 0.2),
                       0.5 * t, false},
                  kPress_m));
    }
    return RunTwoLevelProbe(model, tools);
  }
  const SolverKind solvers[] = {SolverKind::kCg, SolverKind::kPcgJacobi, SolverKind::kPcgIc,
                                SolverKind::kPcgDic, SolverKind::kCholmod};
  const NavierDomain domain{kDomain_m, kDomain_m, 1 * kPascalPerNewtonPerCm2, 1 * kMetrePerCm};
  std::vector<Run> runs;
  std::vector<Distribution> distributions;
  std::vector<std::pair<std::string, std::vector<double>>> navier_density;  // case → q samples
  std::vector<std::pair<std::string, double>> navier_force;
  for (const Case& c : kCases) {
    if (opt.moving_only) break;
    std::optional<NavierBar> navier;
    if (c.has_navier) {
      navier.emplace(domain, c.cx_m - kBarLength_m / 2, c.cx_m + kBarLength_m / 2, c.cy_m,
                     -kPress_m, 40);
      navier_force.emplace_back(c.name, navier->TotalForce_N());
      std::vector<double> q;
      for (int i = 0; i <= 200; ++i) {
        const double x = c.cx_m - kBarLength_m / 2 + kBarLength_m * (i + 0.5) / 201.5;
        q.push_back(x);
        q.push_back(navier->LoadDensity_N_per_m(x));
      }
      navier_density.emplace_back(c.name, q);
    }
    // Reference field on the level-5 grid (33 × 33 nodes), except the row on the bar's line
    // where the series converges only algebraically.
    constexpr int kFieldLevel = 5;
    const int field_side = (1 << kFieldLevel) + 1;
    const double field_h = kDomain_m / (1 << kFieldLevel);
    std::vector<double> field_ref(field_side * field_side, kNaN);
    if (navier) {
      for (int j = 1; j + 1 < field_side; ++j) {
        if (std::abs(j * field_h - c.cy_m) < 1e-9) continue;
        for (int i = 1; i + 1 < field_side; ++i)
          field_ref[j * field_side + i] = navier->Displacement_m(i * field_h, j * field_h);
      }
    }
    for (int level = 1; level <= opt.max_level; ++level) {
      for (MeshKind mesh : {MeshKind::kFine, MeshKind::kMultiscale}) {
        for (SolverKind solver : solvers) {
          const TissueModel model =
              BuildTissueModel(StudyDef(level, mesh, solver, opt.grading, opt.end_resolution));
          Run run;
          run.case_name = c.name;
          run.mesh = ToString(mesh);
          run.solver = ToString(solver);
          run.level = level;
          {  // accuracy: one cold step at exactly 1 cm
            TissueWorkspace ws(model);
            TissueState state = MakeTissueState(model);
            StepTissue(model, BarTool(c, kPress_m), ws, state);
            run.status = ToString(state.status);
            run.unknowns = ws.stats.unknowns;
            run.contacts = state.num_contacts;
            run.residual = ws.stats.relative_residual;
            run.force_N = -state.f_T_S.z();  // force of the tool on the tissue
            if (navier) {
              run.force_error =
                  std::abs(run.force_N - navier->TotalForce_N()) / std::abs(navier->TotalForce_N());
              const double h = model.CellSizeX_m(level);
              bool on_line = state.num_contacts > 0;
              double num = 0, den = 0;
              Distribution dist{c.name, run.mesh, level, {}, {}, {}};
              for (int k = 0; k < state.num_contacts; ++k) {
                const int node = state.contact_nodes[k];
                if (std::abs(model.NodeY_m(node) - c.cy_m) > 1e-9) on_line = false;
                const double x = model.NodeX_m(node);
                const double ref = navier->HatForce_N(x, h);
                num += (state.contact_force_N[k] - ref) * (state.contact_force_N[k] - ref);
                den += ref * ref;
                dist.x_m.push_back(x);
                dist.f_N.push_back(state.contact_force_N[k]);
                dist.ref_N.push_back(ref);
              }
              if (on_line && den > 0) run.nodal_rms = std::sqrt(num / den);
              std::vector<double> field, scratch;
              CalcDisplacementGrid(model, state, kFieldLevel, scratch, field);
              double sum2 = 0;
              int count = 0;
              for (int j = 0; j < field_side; ++j) {
                for (int i = 0; i < field_side; ++i) {
                  const double ref = field_ref[j * field_side + i];
                  if (std::isnan(ref)) continue;
                  const double w = field[j * field_side + i];
                  sum2 += (w - ref) * (w - ref);
                  ++count;
                }
              }
              run.rms = std::sqrt(sum2 / count) / kPress_m;
              if (solver == SolverKind::kCholmod) distributions.push_back(dist);
            }
          }
          TimeRun(model, c, /*reuse_values=*/false, opt, run);
          TimeRun(model, c, /*reuse_values=*/true, opt, run);
          std::fprintf(
              stderr, "%s L%d %-10s %-10s n=%6d step %10.1f us cached %9.1f us rms %s F %s\n",
              c.name, level, run.mesh.c_str(), run.solver.c_str(), run.unknowns, run.step_us,
              run.cached_step_us, JsonNumber(run.rms).c_str(), JsonNumber(run.force_error).c_str());
          runs.push_back(run);
        }
      }
    }
  }

  // The tool sweeping across the tissue at about 1 m/s (1 mm per 1 kHz step, the order of a
  // level-7 cell) while turning, so the mesh and the contact nodes change every step. Against
  // it, in the same run and interleaved in blocks so both see the same machine load, the same
  // model with the tool held still (its depth oscillating: the right-hand side changes, the
  // pattern stays; values re-assembled and re-factorised every step as in step_us).
  std::vector<Moving> moving;
  struct Variant {
    SolverKind solver;
    Ordering ordering;
    ToolConstraint constraint = ToolConstraint::kPenaltyPoints;
    bool attached = true;
  };
  const Variant variants[] = {
      {SolverKind::kPcgDic, Ordering::kNestedDissection, ToolConstraint::kPenaltyPoints, false},
      {SolverKind::kCg, Ordering::kNestedDissection},
      {SolverKind::kPcgJacobi, Ordering::kNestedDissection},
      {SolverKind::kPcgIc, Ordering::kNestedDissection},
      {SolverKind::kPcgDic, Ordering::kNestedDissection},
      {SolverKind::kPcgIc, Ordering::kNestedDissection, ToolConstraint::kNearestNodes},
      {SolverKind::kCholmod, Ordering::kAmd},
      {SolverKind::kCholmod, Ordering::kNestedDissection}};
  for (int level = std::max(1, opt.max_level - 1); level <= opt.max_level; ++level) {
    for (const Variant& v : variants) {
      if (opt.moving_only && (v.solver == SolverKind::kCholmod || v.solver == SolverKind::kCg ||
                              v.constraint != ToolConstraint::kPenaltyPoints))
        continue;
      TissueDef def =
          StudyDef(level, MeshKind::kMultiscale, v.solver, opt.grading, opt.end_resolution);
      def.ordering = v.ordering;
      def.tool_constraint = v.constraint;
      def.attached_mesh = v.attached;
      const TissueModel model = BuildTissueModel(def);
      TissueWorkspace ws(model), ws_static(model);
      ws_static.reuse_values = false;
      TissueState state = MakeTissueState(model), state_static = MakeTissueState(model);
      std::vector<double> us, us_static, select, assemble, solve, cpu, iterations;
      int reused = 0, failed = 0, twisted = 0, reattached = 0;
      double unknowns = 0;
      auto pose = [](int k) {
        const double t = 1e-3 * k;
        const double cx = 0.06 + 0.08 * (0.5 - 0.5 * std::cos(2 * std::numbers::pi * t / 0.16));
        return Case{"moving", cx, 0.10 + 0.03 * std::sin(2 * std::numbers::pi * t / 0.2), 0.5 * t,
                    false};
      };
      constexpr int kBlock = 20;
      const int steps = opt.min_steps * 20;
      for (int k = 0; k < steps + 5; ++k) {
        if (k >= 5 && k % kBlock == 0) {  // a block of static steps
          for (int j = 0; j < kBlock; ++j) {
            const double depth = kPress_m * (1 + 0.1 * std::sin(2 * std::numbers::pi * j / 16));
            StepTissue(model, BarTool(pose(0), depth), ws_static, state_static);
            if (state_static.step > 2) us_static.push_back(ws_static.stats.total_us);
          }
        }
        const double cpu_begin_us = ThreadCpuMicroseconds();
        StepTissue(model, BarTool(pose(k), kPress_m), ws, state);
        const double cpu_us = ThreadCpuMicroseconds() - cpu_begin_us;
        if (k < 5) continue;
        us.push_back(ws.stats.total_us);
        cpu.push_back(cpu_us);
        select.push_back(ws.stats.select_us);
        assemble.push_back(ws.stats.assemble_us);
        solve.push_back(ws.stats.solve_us);
        iterations.push_back(ws.stats.iterations);
        reused += ws.stats.pattern_reused;
        twisted += ws.map.twist.turn_rad != 0;
        reattached += ws.stats.mesh_reattached;
        failed += !IsGood(state.status);
        unknowns += ws.stats.unknowns;
      }
      moving.push_back({level,
                        ToString(v.solver),
                        ToString(v.ordering),
                        ToString(v.constraint),
                        v.attached,
                        Median(us),
                        Percentile(us, 0.99),
                        *std::max_element(us.begin(), us.end()),
                        static_cast<double>(reused) / us.size(),
                        failed,
                        static_cast<int>(us.size()),
                        unknowns / us.size(),
                        Median(select),
                        Median(assemble),
                        Median(solve),
                        Median(cpu),
                        Percentile(cpu, 0.99),
                        Median(us_static),
                        Median(iterations),
                        static_cast<double>(twisted) / us.size(),
                        reattached});
      std::fprintf(stderr,
                   "moving L%d %-10s %-17s %-14s %-8s median %7.1f us (select %6.1f assemble %6.1f "
                   "solve %6.1f) p99 %7.1f  static %7.1f us  cpu %7.1f p99 %7.1f  n=%.0f  it %.0f  "
                   "twisted %.2f reattached %d\n",
                   level, ToString(v.solver), ToString(v.ordering), ToString(v.constraint),
                   v.attached ? "attached" : "grid", moving.back().median_us,
                   moving.back().select_us, moving.back().assemble_us, moving.back().solve_us,
                   moving.back().p99_us, moving.back().static_median_us,
                   moving.back().cpu_median_us, moving.back().cpu_p99_us,
                   moving.back().mean_unknowns, moving.back().iterations,
                   moving.back().twisted_fraction, moving.back().reattached);
    }
  }

  ContactReportOptions contact_options;
  contact_options.max_level = opt.max_level;
  contact_options.quick = opt.max_level < 7;
  contact_options.plot_dir = opt.plot_dir;
  const ContactReport contact =
      opt.moving_only ? ContactReport{"[]", "[]", "{}"} : RunContactReport(contact_options);

  auto find = [&](const std::string& cs, int level, const std::string& mesh,
                  const std::string& solver) -> const Run* {
    for (const Run& r : runs) {
      if (r.case_name == cs && r.level == level && r.mesh == mesh && r.solver == solver) return &r;
    }
    return nullptr;
  };

  // Goals of the issue, evaluated on this run's measurements.
  auto best_ms = [&](int level) {
    double best = kNaN;
    std::string name;
    for (SolverKind s : solvers) {
      const Run* r = find("G1", level, "multiscale", ToString(s));
      if (r && (std::isnan(best) || r->step_us < best)) {
        best = r->step_us;
        name = ToString(s);
      }
    }
    return std::make_pair(best, name);
  };
  std::string goals = "{";
  {
    const int l7 = std::min(7, opt.max_level), l8 = std::min(8, opt.max_level);
    auto [b7, s7] = best_ms(l7);
    auto [b8, s8] = best_ms(l8);
    goals += "\"level_for_500us_goal\": " + std::to_string(l7) +
             ", \"best_multiscale_step_us\": " + JsonNumber(b7) + ", \"best_solver\": \"" + s7 +
             "\", \"goal_500us_met\": " + (b7 <= 500 ? "true" : "false");
    goals += ", \"level_for_1ms_goal\": " + std::to_string(l8) +
             ", \"best_multiscale_step_us_top\": " + JsonNumber(b8) + ", \"best_solver_top\": \"" +
             s8 + "\", \"goal_1ms_met\": " + (b8 <= 1000 ? "true" : "false");
    double min_speedup = kNaN;
    std::string speedups;
    for (SolverKind s : solvers) {
      const Run* f = find("G1", l7, "fine", ToString(s));
      const Run* m = find("G1", l7, "multiscale", ToString(s));
      if (!f || !m) continue;
      const double sp = f->step_us / m->step_us;
      if (!speedups.empty()) speedups += ", ";
      speedups += "\"";
      speedups += ToString(s);
      speedups += "\": ";
      speedups += JsonNumber(sp);
      if (std::isnan(min_speedup) || sp < min_speedup) min_speedup = sp;
    }
    goals += ", \"speedup_by_solver\": {" + speedups +
             "}, \"min_speedup\": " + JsonNumber(min_speedup) +
             ", \"goal_speedup_20x_met\": " + (min_speedup >= 20 ? "true" : "false");
    bool rms_ok = true, force_ok = true;
    for (int level = 1; level <= opt.max_level; ++level) {
      const Run* f = find("G1", level, "fine", "cholmod");
      const Run* m = find("G1", level, "multiscale", "cholmod");
      if (level <= 6 && f && m && std::isfinite(f->rms) && !(m->rms <= 1.5 * f->rms))
        rms_ok = false;
      for (const char* cs : {"G1", "G2"}) {  // the multi-scale mesh (end-graded)
        const Run* r = find(cs, level, "multiscale", "cholmod");
        if (level >= 5 && r && !(r->force_error <= 0.02)) force_ok = false;
      }
    }
    goals += std::string(", \"goal_g1_rms_within_1p5x_fine_met\": ") + (rms_ok ? "true" : "false");
    goals += std::string(", \"goal_multiscale_force_within_2pct_from_level5_met\": ") +
             (force_ok ? "true" : "false");
    double best_moving = kNaN, static_of_best = kNaN;
    std::string best_moving_solver;
    for (const Moving& m : moving) {
      if (m.level != l7 || m.constraint != "penalty_points") continue;
      if (std::isnan(best_moving) || m.median_us < best_moving) {
        best_moving = m.median_us;
        static_of_best = m.static_median_us;
        best_moving_solver = m.solver + "/" + m.ordering;
      }
    }
    goals += ", \"best_moving_step_us\": " + JsonNumber(best_moving) +
             ", \"static_step_us_same_solver\": " + JsonNumber(static_of_best) +
             ", \"best_moving_solver\": \"" + best_moving_solver +
             "\", \"goal_moving_500us_met\": " + (best_moving <= 500 ? "true" : "false");
    // What a station runs: pcg_dic, penalty points, the attached mesh.
    auto station = [&](int level) -> const Moving* {
      for (const Moving& m : moving) {
        if (m.level == level && m.solver == "pcg_dic" && m.constraint == "penalty_points" &&
            m.attached)
          return &m;
      }
      return nullptr;
    };
    const Moving* st7 = station(l7);
    const Moving* st8 = station(l8);
    const bool station_l7 = st7 && st7->median_us <= 500 && st7->p99_us <= 1000;
    const bool station_l8 = st8 && st8->median_us <= 1000;
    goals +=
        ", \"station_moving_l7_median_us\": " + JsonNumber(st7 ? st7->median_us : kNaN) +
        ", \"station_moving_l7_p99_us\": " + JsonNumber(st7 ? st7->p99_us : kNaN) +
        ", \"station_moving_l8_median_us\": " + JsonNumber(st8 ? st8->median_us : kNaN) +
        ", \"station_moving_l7_cpu_median_us\": " + JsonNumber(st7 ? st7->cpu_median_us : kNaN) +
        ", \"station_moving_l7_cpu_p99_us\": " + JsonNumber(st7 ? st7->cpu_p99_us : kNaN) +
        ", \"station_moving_l8_cpu_median_us\": " + JsonNumber(st8 ? st8->cpu_median_us : kNaN) +
        ", \"goal_station_moving_l7_500us_p99_1ms_met\": " + (station_l7 ? "true" : "false") +
        ", \"goal_station_moving_l8_1ms_met\": " + (station_l8 ? "true" : "false");
    goals += std::string(", \"goal_off_grid_within_2pct_met\": ") +
             (contact.off_grid_within_2pct ? "true" : "false");
    goals +=
        std::string(", \"goal_continuity_met\": ") + (contact.continuity_met ? "true" : "false");
  }
  goals += "}";

  // The fair comparisons beside the level-for-level speed-up: the multi-scale mesh against the
  // coarsest fine mesh that is at least as accurate (resultant against Navier), same solver;
  // and, at the same mesh, the station's pcg_dic against CHOLMOD.
  std::string fair = "[";
  std::fprintf(stderr,
               "equal accuracy (G1, resultant error vs Navier): multi-scale level L "
               "against the coarsest fine level at least as accurate\n");
  for (SolverKind s : solvers) {
    for (int level = 4; level <= opt.max_level; ++level) {
      const Run* m = find("G1", level, "multiscale", ToString(s));
      if (!m || !std::isfinite(m->force_error)) continue;
      const Run* f_equal = nullptr;
      for (int lf = 1; lf <= opt.max_level && !f_equal; ++lf) {
        const Run* f = find("G1", lf, "fine", ToString(s));
        if (f && f->force_error <= m->force_error) f_equal = f;
      }
      const Run* f_same = find("G1", level, "fine", ToString(s));
      const Run* chol = find("G1", level, "multiscale", "cholmod");
      const double level_gain = f_same ? f_same->step_us / m->step_us : kNaN;
      const double equal_gain = f_equal ? f_equal->step_us / m->step_us : kNaN;
      const double over_cholmod = chol ? m->step_us / chol->step_us : kNaN;
      std::fprintf(stderr,
                   "  %-10s L%d  error %.3g  %7.1f us | same level fine %8.1f us (x%.1f) | "
                   "fine level %s with error %.3g: %.1f us (x%.1f) | / cholmod %.2f\n",
                   ToString(s), level, m->force_error, m->step_us, f_same ? f_same->step_us : kNaN,
                   level_gain, f_equal ? std::to_string(f_equal->level).c_str() : "none",
                   f_equal ? f_equal->force_error : kNaN, f_equal ? f_equal->step_us : kNaN,
                   equal_gain, over_cholmod);
      if (fair.size() > 1) fair += ", ";
      fair += "{\"solver\": \"" + std::string(ToString(s)) +
              "\", \"level\": " + std::to_string(level) +
              ", \"multiscale_force_error\": " + JsonNumber(m->force_error) +
              ", \"multiscale_step_us\": " + JsonNumber(m->step_us) +
              ", \"speedup_same_level\": " + JsonNumber(level_gain) +
              ", \"fine_level_equal_accuracy\": " +
              (f_equal ? std::to_string(f_equal->level) : std::string("null")) +
              ", \"speedup_equal_accuracy\": " + JsonNumber(equal_gain) +
              ", \"step_over_cholmod\": " + JsonNumber(over_cholmod) + "}";
    }
  }
  fair += "]";

  std::FILE* out = stdout;
  if (!opt.json.empty()) {
    out = std::fopen(opt.json.c_str(), "w");
    if (!out) throw std::invalid_argument("--json " + opt.json + ": cannot open for writing");
  }
  std::fprintf(out,
               "{\n  \"bench\": \"fem\",\n  \"domain_m\": %s, \"shear_modulus_Pa\": %s, "
               "\"thickness_m\": %s, \"bar_length_m\": %s, \"press_m\": %s, \"grading\": %s, "
               "\"end_resolution\": %s,\n",
               JsonNumber(kDomain_m).c_str(), JsonNumber(1e4).c_str(), JsonNumber(0.01).c_str(),
               JsonNumber(kBarLength_m).c_str(), JsonNumber(kPress_m).c_str(),
               JsonNumber(opt.grading).c_str(), JsonNumber(opt.end_resolution).c_str());
  std::fprintf(out, "  \"navier_force_N\": {");
  for (size_t i = 0; i < navier_force.size(); ++i)
    std::fprintf(out, "%s\"%s\": %s", i ? ", " : "", navier_force[i].first.c_str(),
                 JsonNumber(-navier_force[i].second).c_str());
  std::fprintf(out, "},\n  \"goals\": %s,\n  \"fair_comparisons\": %s,\n", goals.c_str(),
               fair.c_str());
  std::fprintf(out,
               "  \"continuity\": %s,\n  \"off_grid\": %s,\n  \"tilted\": %s,\n  \"runs\": [\n",
               contact.continuity.c_str(), contact.off_grid.c_str(), contact.tilted.c_str());
  for (size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    std::fprintf(out,
                 "    {\"case\": \"%s\", \"level\": %d, \"mesh\": \"%s\", \"solver\": \"%s\", "
                 "\"unknowns\": %d, \"contact_nodes\": %d, \"step_us\": %s, "
                 "\"cached_step_us\": %s, \"select_us\": %s, \"assemble_us\": %s, "
                 "\"solve_us\": %s, \"forces_us\": %s, \"iterations\": %d, \"steps\": %d, "
                 "\"relative_residual\": %s, \"force_N\": %s, \"rms_error_vs_navier\": %s, "
                 "\"nodal_force_rms_error\": %s, "
                 "\"resultant_force_error\": %s, \"status\": \"%s\"}%s\n",
                 r.case_name.c_str(), r.level, r.mesh.c_str(), r.solver.c_str(), r.unknowns,
                 r.contacts, JsonNumber(r.step_us).c_str(), JsonNumber(r.cached_step_us).c_str(),
                 JsonNumber(r.select_us).c_str(), JsonNumber(r.assemble_us).c_str(),
                 JsonNumber(r.solve_us).c_str(), JsonNumber(r.forces_us).c_str(), r.iterations,
                 r.steps, JsonNumber(r.residual).c_str(), JsonNumber(r.force_N).c_str(),
                 JsonNumber(r.rms).c_str(), JsonNumber(r.nodal_rms).c_str(),
                 JsonNumber(r.force_error).c_str(), r.status.c_str(),
                 i + 1 < runs.size() ? "," : "");
  }
  std::fprintf(out, "  ],\n  \"moving\": [\n");
  for (size_t i = 0; i < moving.size(); ++i) {
    const Moving& m = moving[i];
    std::fprintf(
        out,
        "    {\"level\": %d, \"mesh\": \"multiscale\", \"solver\": \"%s\", "
        "\"ordering\": \"%s\", \"tool_constraint\": \"%s\", \"attached_mesh\": %s, "
        "\"steps\": %d, \"median_us\": %s, \"p99_us\": %s, "
        "\"max_us\": %s, \"select_us\": %s, \"assemble_us\": %s, \"solve_us\": %s, "
        "\"static_median_us\": %s, \"pattern_reuse_fraction\": %s, "
        "\"failed_steps\": %d, \"mean_unknowns\": %s, \"cpu_median_us\": %s, "
        "\"cpu_p99_us\": %s, \"median_iterations\": %s, \"twisted_fraction\": %s, "
        "\"reattached_steps\": %d}%s\n",
        m.level, m.solver.c_str(), m.ordering.c_str(), m.constraint.c_str(),
        m.attached ? "true" : "false", m.steps, JsonNumber(m.median_us).c_str(),
        JsonNumber(m.p99_us).c_str(), JsonNumber(m.max_us).c_str(), JsonNumber(m.select_us).c_str(),
        JsonNumber(m.assemble_us).c_str(), JsonNumber(m.solve_us).c_str(),
        JsonNumber(m.static_median_us).c_str(), JsonNumber(m.reuse_fraction).c_str(), m.failed,
        JsonNumber(m.mean_unknowns).c_str(), JsonNumber(m.cpu_median_us).c_str(),
        JsonNumber(m.cpu_p99_us).c_str(), JsonNumber(m.iterations).c_str(),
        JsonNumber(m.twisted_fraction).c_str(), m.reattached, i + 1 < moving.size() ? "," : "");
  }
  std::fprintf(out, "  ],\n  \"force_distribution\": [\n");
  for (size_t i = 0; i < distributions.size(); ++i) {
    const Distribution& d = distributions[i];
    std::string xs, fs, rs;
    for (size_t k = 0; k < d.x_m.size(); ++k) {
      if (k > 0) {
        xs += ", ";
        fs += ", ";
        rs += ", ";
      }
      xs += JsonNumber(d.x_m[k]);
      fs += JsonNumber(d.f_N[k]);
      rs += JsonNumber(d.ref_N[k]);
    }
    std::fprintf(out,
                 "    {\"case\": \"%s\", \"level\": %d, \"mesh\": \"%s\", \"x_m\": [%s], "
                 "\"force_N\": [%s], \"navier_N\": [%s]}%s\n",
                 d.case_name.c_str(), d.level, d.mesh.c_str(), xs.c_str(), fs.c_str(), rs.c_str(),
                 i + 1 < distributions.size() ? "," : "");
  }
  std::fprintf(out, "  ]\n}\n");
  if (out != stdout) std::fclose(out);

  if (!opt.plot_dir.empty()) {
    namespace fs = std::filesystem;
    fs::create_directories(opt.plot_dir);
    const std::string dir = opt.plot_dir + "/";
    if (std::FILE* f = std::fopen((dir + "fem_runs.csv").c_str(), "w")) {
      std::fprintf(f,
                   "case,level,mesh,solver,unknowns,step_us,cached_step_us,rms_error_vs_navier,"
                   "resultant_force_error,force_N,iterations\n");
      for (const Run& r : runs)
        std::fprintf(f, "%s,%d,%s,%s,%d,%s,%s,%s,%s,%s,%d\n", r.case_name.c_str(), r.level,
                     r.mesh.c_str(), r.solver.c_str(), r.unknowns, JsonNumber(r.step_us).c_str(),
                     JsonNumber(r.cached_step_us).c_str(), JsonNumber(r.rms).c_str(),
                     JsonNumber(r.force_error).c_str(), JsonNumber(r.force_N).c_str(),
                     r.iterations);
      std::fclose(f);
    }
    // Per-figure data files for gnuplot (blank-line separated blocks, NaN as "?").
    auto q = [](double v) { return std::isfinite(v) ? JsonNumber(v) : std::string("?"); };
    if (std::FILE* f = std::fopen((dir + "fig3_5_force_G1.dat").c_str(), "w")) {
      for (const auto& [name, qs] : navier_density) {
        if (name != "G1") continue;
        std::fprintf(f, "# navier x_cm q_N_per_cm\n");
        for (size_t k = 0; k + 1 < qs.size(); k += 2)
          std::fprintf(f, "%s %s\n", q(qs[k] * 100).c_str(), q(-qs[k + 1] / 100).c_str());
      }
      // Nodal force over the node's share of the bar (half the distance to each neighbour):
      // the end-graded multi-scale mesh has finer contact spacing near the ends.
      for (const Distribution& d : distributions) {
        if (d.case_name != "G1") continue;
        std::vector<size_t> order(d.x_m.size());
        for (size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::sort(order.begin(), order.end(),
                  [&](size_t a, size_t b) { return d.x_m[a] < d.x_m[b]; });
        std::fprintf(f, "\n\n# %s level %d: x_cm f/share N_per_cm\n", d.mesh.c_str(), d.level);
        for (size_t k = 0; k < order.size(); ++k) {
          const double left = k > 0 ? d.x_m[order[k]] - d.x_m[order[k - 1]] : 0;
          const double right = k + 1 < order.size() ? d.x_m[order[k + 1]] - d.x_m[order[k]] : 0;
          // A lone contact node carries the whole bar.
          const double share_cm =
              order.size() > 1 ? 100 * 0.5 * (left + right) : 100 * kBarLength_m;
          std::fprintf(f, "%s %s\n", q(d.x_m[order[k]] * 100).c_str(),
                       q(-d.f_N[order[k]] / share_cm).c_str());
        }
      }
      std::fclose(f);
    }
    if (std::FILE* f = std::fopen((dir + "fig3_6_rms.csv").c_str(), "w")) {
      std::fprintf(f, "level,G1_fine,G1_multiscale,G2_fine,G2_multiscale\n");
      for (int level = 1; level <= opt.max_level; ++level) {
        std::fprintf(f, "%d", level);
        for (const char* cs : {"G1", "G2"})
          for (const char* mk : {"fine", "multiscale"}) {
            const Run* r = find(cs, level, mk, "cholmod");
            std::fprintf(f, ",%s", q(r ? r->rms : kNaN).c_str());
          }
        std::fprintf(f, "\n");
      }
      std::fclose(f);
    }
    if (std::FILE* f = std::fopen((dir + "fig3_7_time.csv").c_str(), "w")) {
      std::fprintf(f, "level");
      for (SolverKind s : solvers)
        for (const char* mk : {"fine", "multiscale"}) std::fprintf(f, ",%s_%s", mk, ToString(s));
      std::fprintf(f, "\n");
      for (int level = 1; level <= opt.max_level; ++level) {
        std::fprintf(f, "%d", level);
        for (SolverKind s : solvers)
          for (const char* mk : {"fine", "multiscale"}) {
            const Run* r = find("G1", level, mk, ToString(s));
            std::fprintf(f, ",%s", q(r ? r->step_us : kNaN).c_str());
          }
        std::fprintf(f, "\n");
      }
      std::fclose(f);
    }
    if (std::FILE* f = std::fopen((dir + "fig3_8_speedup.csv").c_str(), "w")) {
      std::fprintf(f, "level");
      for (const Case& c : kCases)
        for (SolverKind s : solvers) std::fprintf(f, ",%s_%s", c.name, ToString(s));
      std::fprintf(f, "\n");
      for (int level = 1; level <= opt.max_level; ++level) {
        std::fprintf(f, "%d", level);
        for (const Case& c : kCases)
          for (SolverKind s : solvers) {
            const Run* fr = find(c.name, level, "fine", ToString(s));
            const Run* mr = find(c.name, level, "multiscale", ToString(s));
            std::fprintf(f, ",%s", q(fr && mr ? fr->step_us / mr->step_us : kNaN).c_str());
          }
        std::fprintf(f, "\n");
      }
      std::fclose(f);
    }
    if (std::FILE* f = std::fopen((dir + "fem_plots.gp").c_str(), "w")) {
      std::fprintf(f,
                   "set terminal pngcairo size 900,600\nset datafile separator ','\n"
                   "set key autotitle columnhead\nset grid\n"
                   "set output '%sfig3_6_rms.png'\nset logscale y\nset xlabel 'mesh level'\n"
                   "set ylabel 'relative RMS error of nodal force vs Navier'\n"
                   "plot for [i=2:5] '%sfig3_6_rms.csv' using 1:i with linespoints\n"
                   "set output '%sfig3_7_time.png'\nset ylabel 'step time (us), case G1'\n"
                   "plot for [i=2:9] '%sfig3_7_time.csv' using 1:i with linespoints\n"
                   "set output '%sfig3_8_speedup.png'\nunset logscale y\n"
                   "set ylabel 'speed-up fine / multi-scale'\n"
                   "plot for [i=2:13] '%sfig3_8_speedup.csv' using 1:i with linespoints\n"
                   "set output '%sfig3_5_force_G1.png'\nset datafile separator whitespace\n"
                   "set key noautotitle\nset xlabel 'x (cm)'\nset ylabel 'line force (N/cm)'\n"
                   "set yrange [0:*]\n"
                   "plot '%sfig3_5_force_G1.dat' index 0 with lines lw 2 title 'Navier', "
                   "for [b=1:%d] '' index b with linespoints title sprintf('%%s L%%d', (b %% 2 == "
                   "1 ? 'fine' : 'multi-scale'), (b + 1) / 2)\n",
                   dir.c_str(), dir.c_str(), dir.c_str(), dir.c_str(), dir.c_str(), dir.c_str(),
                   dir.c_str(), dir.c_str(), 2 * opt.max_level);
      std::fclose(f);
      const std::string cmd = "gnuplot '" + dir + "fem_plots.gp' 2>&1";
      if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "fem: gnuplot failed\n");
    }
  }
  return 0;
}

}  // namespace
}  // namespace microdex::fem

MICRODEX_REGISTER_BENCH(fem, "fem",
                        "multi-scale FEM study (thesis fig 3.5-3.8): error and time by level",
                        microdex::fem::RunFem);
