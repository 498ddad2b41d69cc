// microdex-bench knot: the recognised knot of an OBJ polyline (README.md "Command-line
// contracts"; a thread through the tissue gets the class of the knot tied around its stitch),
// --speed, the cost of recognition against thread length (common/knot/README.md "Speed"), and
// --stitch-report, the stitch-knot confusion matrix and timings (common/knot/README.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "common/knot/invariants.h"
#include "common/knot/obj.h"
#include "common/knot/recognition.h"
#include "common/knot/stitch_knot.h"
#include "common/knot/stitch_knot_shapes.h"
#include "tests/support/knot_shapes.h"
#include "tests/support/stitch_knot_variants.h"

namespace microdex::bench {
namespace {

using knot::shapes::Curve;
namespace shapes = knot::shapes;

// Thread diameter of the speed cases (10-0 nylon); nodes one diameter apart.
constexpr double kDiameter_m = 3e-5;

// The class of the knot tied around the stitch of a thread through the tissue.
// diameter_m: the thread's (the file's or --thread-diameter); 0, the median link.
int PrintStitchKnot(const std::string& path, const std::vector<Eigen::Vector3d>& nodes,
                    double diameter_m, bool verbose) {
  knot::StitchKnotAnalysis a;
  try {
    a = knot::AnalyzeStitchKnot(nodes, {.thread_diameter_m = diameter_m, .full_evidence = verbose});
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "microdex-bench knot: %s: %s\n", path.c_str(), e.what());
    return 2;
  }
  std::printf("%s\n", std::string(knot::StitchKnotName(a.type)).c_str());
  if (verbose) {
    std::fprintf(stderr,
                 "stitch: nodes %zu, below the tissue %d..%d, diameter %.3g m (%s), total twist "
                 "%.3f turns, Gauss linking %.3f, closure %s%s%s\n",
                 nodes.size(), a.first_below, a.last_below, a.thread_diameter_m,
                 diameter_m > 0 ? "the thread's" : "the median link", a.total_twist_turns,
                 a.gauss_linking, std::string(knot::KnotName(a.closure)).c_str(),
                 a.reason.empty() ? "" : ", ", a.reason.c_str());
    for (std::size_t i = 0; i < a.throws.size(); ++i) {
      const knot::StitchThrow& t = a.throws[i];
      std::fprintf(
          stderr,
          "  %zu: %s %s x%d (twist %+.3f turns), strand straightness %.2f / %.2f, "
          "s = [%.3g, %.3g] m%s\n",
          i + 1, t.hitch ? "half hitch" : "throw", t.hand > 0 ? "right" : "left", t.turns,
          t.twist_turns, t.straightness[0], t.straightness[1], t.start_s_m, t.end_s_m,
          t.hitch ? (t.post_strand == 1 ? ", post: first strand" : ", post: last strand") : "");
    }
  }
  return 0;
}

// thread_diameter_m > 0 overrides the file's diameter.
int PrintKnot(const std::string& path, double thread_diameter_m, bool verbose) {
  std::vector<Eigen::Vector3d> nodes;
  double file_diameter_m = 0.0;
  try {
    nodes = knot::ReadObjPolyline(path, &file_diameter_m);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-bench knot: %s\n", e.what());
    return 2;
  }
  if (knot::IsStitchPolyline(nodes)) {
    return PrintStitchKnot(path, nodes, thread_diameter_m > 0 ? thread_diameter_m : file_diameter_m,
                           verbose);
  }
  knot::KnotAnalysis a;
  try {
    a = knot::AnalyzeKnot(nodes, {.locate = verbose});
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "microdex-bench knot: %s: %s\n", path.c_str(), e.what());
    return 2;
  }
  std::printf("%s\n", std::string(knot::KnotName(a.type)).c_str());
  if (verbose) {
    std::fprintf(stderr,
                 "nodes %zu, reduced vertices %d, crossings %d -> %d, Alexander %s, "
                 "determinant %lld, signature %d, Jones %s, projections %d/%d agree",
                 nodes.size(), a.reduced_vertices, a.raw_crossings, a.crossings,
                 knot::ToString(a.alexander).c_str(), static_cast<long long>(a.determinant),
                 a.signature, a.jones_computed ? knot::ToString(a.jones).c_str() : "(skipped)",
                 a.projections_agreeing, a.projections_tried);
    if (a.located) {
      std::fprintf(stderr, ", core s = [%.6g, %.6g] m", a.core_start_s_m, a.core_end_s_m);
    }
    std::fprintf(stderr, "\n");
  }
  return 0;
}

// A speed case: a thread of `nodes` nodes spaced one diameter apart.
struct SpeedCase {
  std::string name;
  std::function<Curve()> shape;  // open thread in shape units
  const char* expected;
};

std::vector<SpeedCase> SpeedCases() {
  auto long_knot = [](Curve closed) { return shapes::LongKnot(closed, 4.0); };
  return {
      {"trefoil", [=] { return long_knot(shapes::TorusKnot(2, 3, 400)); }, "overhand-right"},
      {"square",
       [=] {
         return shapes::Splice(long_knot(shapes::TorusKnot(2, 3, 400)),
                               long_knot(shapes::TorusKnot(2, 3, 400, true)), 2.0);
       },
       "square"},
      {"surgeons",
       [] {
         return shapes::Splice(shapes::OverhandAsTied(2, true), shapes::OverhandAsTied(1, false),
                               2.0);
       },
       "surgeons"},
      {"coil", [] { return shapes::Coil(12, 1.0, 0.4, 40); }, "none"},
      {"messy-unknot", [] { return shapes::AscendingRandomWalk(400, 0.5, 0.02, 7); }, "none"},
  };
}

double MedianMicroseconds(const std::function<void()>& f, int repeats) {
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(t.begin(), t.begin() + static_cast<long>(t.size() / 2), t.end());
  return t[t.size() / 2];
}

int RunSpeed(const std::vector<int>& sizes, int repeats, const std::string& json_path) {
  std::string json = "{\n  \"diameter_m\": " + std::to_string(kDiameter_m) + ",\n  \"runs\": [";
  std::printf("%-13s %6s %-15s %12s %12s %14s %8s\n", "case", "nodes", "result", "recognize_us",
              "analyze_us", "unreduced_us", "speedup");
  bool first = true;
  int wrong = 0;
  for (const SpeedCase& c : SpeedCases()) {
    const Curve shape = c.shape();
    const double length = shapes::Length(shape);
    for (int n : sizes) {
      const double spacing = length / (n - 1);
      Curve thread = shapes::ResampleOpen(shape, spacing);
      for (auto& p : thread) p *= kDiameter_m / spacing;
      knot::KnotType type = knot::KnotType::kUnknown;
      const double recognize_us =
          MedianMicroseconds([&] { type = knot::RecognizeKnot(thread); }, repeats);
      const double analyze_us =
          MedianMicroseconds([&] { (void)knot::AnalyzeKnot(thread); }, std::max(3, repeats / 4));
      knot::KnotType unreduced_type = knot::KnotType::kUnknown;
      const double unreduced_us = MedianMicroseconds(
          [&] {
            unreduced_type =
                knot::RecognizeKnot(thread, {.reduce_polygon = false, .locate = false});
          },
          std::max(3, repeats / 4));
      const std::string result(knot::KnotName(type));
      if (result != c.expected) ++wrong;
      std::printf("%-13s %6zu %-15s %12.1f %12.1f %14.1f %8.1f\n", c.name.c_str(), thread.size(),
                  result.c_str(), recognize_us, analyze_us, unreduced_us,
                  unreduced_us / recognize_us);
      char row[512];
      std::snprintf(row, sizeof(row),
                    "%s\n    {\"case\": \"%s\", \"nodes\": %zu, \"result\": \"%s\", "
                    "\"expected\": \"%s\", \"recognize_us\": %.2f, \"analyze_us\": %.2f, "
                    "\"unreduced_us\": %.2f, \"unreduced_result\": \"%s\"}",
                    first ? "" : ",", c.name.c_str(), thread.size(), result.c_str(), c.expected,
                    recognize_us, analyze_us, unreduced_us,
                    std::string(knot::KnotName(unreduced_type)).c_str());
      json += row;
      first = false;
    }
  }
  json += "\n  ]\n}\n";
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << json;
    if (!out) {
      std::fprintf(stderr, "microdex-bench knot: cannot write %s\n", json_path.c_str());
      return 2;
    }
  }
  std::printf(
      "(medians over %d runs; recognize = RecognizeKnot, analyze = AnalyzeKnot with the "
      "knotted core, unreduced = no triangle reduction, the baseline)\n",
      repeats);
  if (wrong > 0) std::fprintf(stderr, "microdex-bench knot: %d case(s) misrecognised\n", wrong);
  return wrong > 0 ? 1 : 0;
}

// Confusion matrix of RecogniseStitchKnot over the seeded variants (tests/support
// stitch_knot_variants.h) at each noise level, and the time per recognition of ~2000-node
// threads.
int RunStitchReport(int count, const std::vector<double>& noises, int repeats) {
  namespace variants = knot::variants;
  int wrong = 0;
  for (double noise : noises) {
    variants::ConfusionMatrix confusion{};
    for (std::size_t row = 0; row < variants::kStitchClasses.size(); ++row) {
      for (const auto& v :
           variants::RandomStitchVariants(variants::kStitchClasses[row], count, 77, noise)) {
        const int col = static_cast<int>(knot::RecogniseStitchKnot(v.thread));
        ++confusion[row][col];
        if (col != static_cast<int>(variants::kStitchClasses[row])) ++wrong;
      }
    }
    std::printf("seed 77, %d variants per class, noise +-%.2f diameters:\n%s\n", count, noise,
                variants::FormatConfusion(confusion).c_str());
  }
  std::printf("%-11s %6s %-11s %14s %14s\n", "class", "nodes", "result", "recognise_us",
              "analyse_us");
  for (knot::StitchKnotType kind : variants::kStitchClasses) {
    knot::StitchKnotShapeDef def;
    def.kind = kind;
    def.tightness = 0.5;
    def.tail_length_m = 900.0 * def.thread_diameter_m;  // about 2000 nodes
    def.tail_first_elevation_rad = 0.6;
    def.tail_last_elevation_rad = 0.6;
    const std::vector<Eigen::Vector3d> thread = knot::MakeStitchKnot(def);
    knot::StitchKnotType type = knot::StitchKnotType::kUnknown;
    const double recognise_us =
        MedianMicroseconds([&] { type = knot::RecogniseStitchKnot(thread); }, repeats);
    const double analyse_us =
        MedianMicroseconds([&] { (void)knot::AnalyzeStitchKnot(thread); }, repeats);
    if (type != kind) ++wrong;
    std::printf("%-11s %6zu %-11s %14.1f %14.1f\n", std::string(knot::StitchKnotName(kind)).c_str(),
                thread.size(), std::string(knot::StitchKnotName(type)).c_str(), recognise_us,
                analyse_us);
  }
  std::printf(
      "(medians over %d runs; recognise = RecogniseStitchKnot, analyse = AnalyzeStitchKnot "
      "with the closure's knot type)\n",
      repeats);
  if (wrong > 0)
    std::fprintf(stderr, "microdex-bench knot: %d stitch knot(s) misrecognised\n", wrong);
  return wrong > 0 ? 1 : 0;
}

int RunKnot(int argc, char** argv) {
  CLI::App app{"microdex-bench knot FILE.obj: print the recognised knot of the polyline"};
  std::string file;
  bool speed = false;
  bool verbose = false;
  std::vector<int> sizes = {200, 500, 1000};
  int repeats = 21;
  std::string json;
  bool stitch_report = false;
  int stitch_variants = 60;
  std::vector<double> stitch_noise = {0.15};
  app.add_option("file", file, "OBJ file with the thread as an 'l' element");
  app.add_flag("--stitch-report", stitch_report,
               "confusion matrix and timings of the stitch-knot recogniser instead");
  app.add_option("--variants", stitch_variants, "--stitch-report: variants per class")
      ->check(CLI::Range(1, 100000));
  app.add_option("--noise", stitch_noise, "--stitch-report: noise levels, in thread diameters")
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--speed", speed, "time recognition on reference threads instead");
  app.add_flag("--verbose,-v", verbose, "print the invariants and the knotted core on stderr");
  double thread_diameter_m = 0.0;
  app.add_option("--thread-diameter", thread_diameter_m,
                 "a knot around a stitch: the thread's diameter in metres (default: the file's "
                 "'# thread_diameter_m', else the median link)")
      ->check(CLI::PositiveNumber);
  app.add_option("--nodes", sizes, "--speed: thread sizes")->check(CLI::Range(8, 100000));
  app.add_option("--repeats", repeats, "--speed: runs per median")->check(CLI::Range(1, 10000));
  app.add_option("--json", json, "--speed: write the runs as JSON");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  if (speed) return RunSpeed(sizes, repeats, json);
  if (stitch_report) return RunStitchReport(stitch_variants, stitch_noise, repeats);
  if (file.empty()) {
    std::fprintf(stderr, "microdex-bench knot: expected FILE.obj (or --speed)\n");
    return 2;
  }
  return PrintKnot(file, thread_diameter_m, verbose);
}

}  // namespace

MICRODEX_REGISTER_BENCH(knot, "knot",
                        "recognised knot of an OBJ polyline (or of the knot around its stitch); "
                        "--speed, --stitch-report",
                        RunKnot);

}  // namespace microdex::bench
