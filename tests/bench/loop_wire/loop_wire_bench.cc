// microdex-bench loop_wire: error against run time of the loop-along-a-wire clearance
// (common/geometry/loop_wire.h). The exact query, the sampled baseline at several sample
// counts and FCL on meshes at several resolutions answer the same random poses of a loop on a
// training course; every error is measured against the long-double reference of the unit tests
// (tests/unit/geometry/loop_wire_reference.h). Two families: the loop threaded on the wire
// (centre within R of the axis, tilted up to 60° from the tangent) and far from it (3–30 R).
// Also: the segment–circle minimum by the stationary-point quartic (quartic.h) against the
// bracketed solver on near-degenerate segments.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "bench_util.h"
#include "common/geometry/loop_wire.h"
#include "common/geometry/loop_wire_mesh.h"
#include "common/geometry/loop_wire_sampled.h"
#include "common/geometry/loop_wire_segment.h"
#include "tests/unit/geometry/loop_wire_reference.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::bench {
namespace {

using geometry::LoopWireClearance;
using geometry::LoopWireModel;
using Clock = std::chrono::steady_clock;
constexpr double kPi = std::numbers::pi;

struct Options {
  std::string json;
  int queries = 2000;
  int reps = 7;
  unsigned seed = 1;
  bool quick = false;
};

// The training course: R = 2 mm loop of 0.15 mm wire on a 0.25 mm wire, straight runs and
// turns in three orientations.
geometry::LoopDef TrainingLoop() { return {2e-3, 0.15e-3}; }
geometry::WireDef TrainingWire() {
  using S = geometry::WireCourseStepDef;
  return geometry::MakeWireCourse(
      Eigen::Isometry3d::Identity(),
      {S::Straight(20e-3), S::Turn(10e-3, kPi / 2, 0), S::Straight(10e-3),
       S::Turn(8e-3, 2 * kPi / 3, kPi / 2), S::Straight(15e-3), S::Turn(6e-3, kPi, -kPi / 4),
       S::Straight(20e-3), S::Turn(12e-3, kPi / 3, kPi), S::Straight(10e-3)},
      0.25e-3);
}

struct Family {
  std::string name, what;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<long double> ref_clearance;
};

struct Measure {
  std::string method, setting;
  double ns_per_query = 0;
  double max_error_m = 0, median_error_m = 0;
  int error_queries = 0;         // queries whose error is counted
  double contact_agreement = 1;  // fraction of queries with the reference's contact flag
};

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

Family MakeFamily(bool threaded, int n, std::mt19937_64& rng, const geometry::LoopDef& loop,
                  const geometry::WireDef& wire, ProgressLine* progress) {
  const geometry::testing::RandomLoopWire scene{loop, wire};
  const LoopWireModel model(loop, wire);
  Family f;
  f.name = threaded ? "threaded" : "far";
  f.what = threaded ? "loop threaded on the wire: centre within R of the axis, tilt <= 60 deg"
                    : "loop 3-30 R from the wire, any orientation";
  const double R = loop.radius_m;
  std::uniform_real_distribution<double> u01(0, 1);
  double length = 0;
  for (const auto& p : wire.pieces) length += p.Length();
  while (static_cast<int>(f.poses.size()) < n) {
    Eigen::Isometry3d X = threaded ? geometry::testing::MakeThreadedPose(rng, scene, R, kPi / 3)
                                   : geometry::testing::MakeWidePose(rng, scene, 0);
    if (!threaded) {
      const Eigen::Vector3d dir = geometry::testing::RandomRotation(rng) * Eigen::Vector3d::UnitX();
      X.translation() += (3 + 27 * u01(rng)) * R * dir;
    }
    // Away from the course's ends (the analytic wire ends in a round cap, the mesh tube is
    // open): neither the loop's centre nor the nearest wire point at an end.
    const geometry::WireProgress pr = geometry::CalcWireProgress(model, X.translation());
    if (pr.s_m < 3 * R || pr.s_m > length - 3 * R) continue;
    const geometry::LoopWireClearance c = geometry::CalcLoopWireClearance(model, X);
    if (c.s_m < 1e-9 * length || c.s_m > (1 - 1e-9) * length) continue;
    f.poses.push_back(X);
    f.ref_clearance.push_back(geometry::testing::CalcLoopWireReference(loop, wire, X).distance_m -
                              loop.wire_radius_m - wire.radius_m);
    if (f.poses.size() % 50 == 0) progress->Step("reference, " + f.name);
  }
  return f;
}

Measure Evaluate(const std::string& method, const std::string& setting, const Family& f,
                 const std::vector<LoopWireClearance>& res, bool only_disjoint, double ns) {
  Measure m;
  m.method = method;
  m.setting = setting;
  m.ns_per_query = ns;
  std::vector<double> err;
  int agree = 0;
  for (std::size_t i = 0; i < res.size(); ++i) {
    const bool ref_contact = f.ref_clearance[i] <= 0;
    agree += res[i].contact == ref_contact;
    if (only_disjoint && (res[i].contact || ref_contact)) continue;
    err.push_back(static_cast<double>(
        std::abs(static_cast<long double>(res[i].clearance_m) - f.ref_clearance[i])));
  }
  m.error_queries = static_cast<int>(err.size());
  m.max_error_m = err.empty() ? std::nan("") : *std::max_element(err.begin(), err.end());
  m.median_error_m = Median(err);
  m.contact_agreement = static_cast<double>(agree) / static_cast<double>(res.size());
  return m;
}

// The quartic check: max |distance| error of the quartic and bracketed segment solvers against
// the reference on near-degenerate segments (units of R, 1 = R).
struct QuarticCheck {
  std::string family;
  double brackets_max = 0, quartic_max = 0;
  int cases = 0;
};

std::vector<QuarticCheck> RunQuarticCheck(std::mt19937_64& rng, int cases) {
  std::uniform_real_distribution<double> u(-1, 1);
  const geometry::LoopDef loop{1, 0.1};
  std::vector<QuarticCheck> out;
  const auto run = [&](const std::string& name, auto make) {
    QuarticCheck q;
    q.family = name;
    for (int i = 0; i < cases; ++i) {
      Eigen::Vector3d a, b;
      make(&a, &b);
      geometry::WireDef w;
      w.radius_m = 0.01;
      w.pieces.push_back(geometry::WirePieceDef::Segment(a, b));
      const double ref = static_cast<double>(
          geometry::testing::CalcLoopWireReference(loop, w, Eigen::Isometry3d::Identity())
              .distance_m);
      const double eb = std::sqrt(geometry::CalcSegmentCircleMin(a, b).dist_sq);
      const double eq = std::sqrt(geometry::CalcSegmentCircleMinQuartic(a, b).dist_sq);
      q.brackets_max = std::max(q.brackets_max, std::abs(eb - ref));
      q.quartic_max = std::max(q.quartic_max, std::abs(eq - ref));
      ++q.cases;
    }
    out.push_back(q);
  };
  const auto exp10 = [&](double lo, double hi) {
    return std::pow(10.0, lo + (hi - lo) * (u(rng) + 1) / 2);
  };
  run("general (random segments within 3 R)", [&](Eigen::Vector3d* a, Eigen::Vector3d* b) {
    *a = 3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    *b = 3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  });
  run("in the loop's plane, outside: h = 1 + 1e-12..1e-2",
      [&](Eigen::Vector3d* a, Eigen::Vector3d* b) {
        const double h = 1 + exp10(-12, -2), phi = kPi * u(rng);
        const Eigen::Vector3d n(std::cos(phi), std::sin(phi), 0), t(-n.y(), n.x(), 0);
        *a = h * n - (2 + u(rng)) * t;
        *b = h * n + (2 + u(rng)) * t;
      });
  run("tilted 1e-12..1e-3 rad out of the plane", [&](Eigen::Vector3d* a, Eigen::Vector3d* b) {
    const double h = 1 + 0.5 * (u(rng) + 1), phi = kPi * u(rng), tilt = exp10(-12, -3);
    const Eigen::Vector3d n(std::cos(phi), std::sin(phi), 0), t(-n.y(), n.x(), 0);
    const Eigen::Vector3d d = std::cos(tilt) * t + std::sin(tilt) * Eigen::Vector3d::UnitZ();
    *a = h * n - 2 * d;
    *b = h * n + 2 * d;
  });
  run("through the axis, 1e-12..1e-3 R from it", [&](Eigen::Vector3d* a, Eigen::Vector3d* b) {
    const double off = exp10(-12, -3);
    const Eigen::Vector3d d = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Eigen::Vector3d p = off * d.unitOrthogonal() + 0.3 * u(rng) * Eigen::Vector3d::UnitZ();
    *a = p - 3 * d;
    *b = p + 3 * d;
  });
  run("nearly parallel to the axis (1e-12..1e-3 rad)", [&](Eigen::Vector3d* a, Eigen::Vector3d* b) {
    const double h = 2 * (u(rng) + 1), tilt = exp10(-12, -3);
    const Eigen::Vector3d d(std::sin(tilt), 0, std::cos(tilt));
    *a = Eigen::Vector3d(h, 0, 0) - 2 * d;
    *b = Eigen::Vector3d(h, 0, 0) + 2 * d;
  });
  return out;
}

int RunReport(const Options& opt) {
  const geometry::LoopDef loop = TrainingLoop();
  const geometry::WireDef wire = TrainingWire();
  const LoopWireModel model(loop, wire);
  const int n = opt.quick ? std::min(opt.queries, 200) : opt.queries;
  const std::vector<int> samples =
      opt.quick ? std::vector<int>{4, 64} : std::vector<int>{4, 16, 64, 256, 1024, 4096};
  std::vector<geometry::LoopWireMeshResolution> meshes = {{32, 8, 8}, {64, 16, 16}};
  if (!opt.quick) {
    meshes.push_back({128, 32, 32});
    meshes.push_back({256, 64, 64});
  }
  const int methods = 1 + static_cast<int>(samples.size() + meshes.size());
  ProgressLine progress(2 * (n / 50) + 2 * methods + 1);
  std::mt19937_64 rng(opt.seed);
  std::vector<Family> families;
  families.push_back(MakeFamily(true, n, rng, loop, wire, &progress));
  families.push_back(MakeFamily(false, n, rng, loop, wire, &progress));
  std::vector<std::unique_ptr<geometry::LoopWireMeshModel>> mesh_models;
  mesh_models.reserve(meshes.size());
  for (const auto& r : meshes) {
    mesh_models.push_back(std::make_unique<geometry::LoopWireMeshModel>(model, r));
  }
  std::vector<std::vector<Measure>> results(families.size());
  std::vector<LoopWireClearance> res(static_cast<std::size_t>(n));
  for (std::size_t fi = 0; fi < families.size(); ++fi) {
    const Family& f = families[fi];
    progress.Step(f.name + ": exact");
    double ns = MedianNsPerQuery(n, opt.reps, 5, [&](int i) {
      res[i] = geometry::CalcLoopWireClearance(model, f.poses[i]);
    });
    results[fi].push_back(Evaluate("exact", "-", f, res, false, ns));
    for (const int s : samples) {
      progress.Step(f.name + ": sampled N = " + std::to_string(s));
      ns = MedianNsPerQuery(n, opt.reps, 5, [&](int i) {
        res[i] = geometry::CalcLoopWireClearanceSampled(model, f.poses[i], s);
      });
      results[fi].push_back(
          Evaluate("sampled", "N = " + std::to_string(s) + " per piece", f, res, false, ns));
    }
    for (std::size_t k = 0; k < meshes.size(); ++k) {
      const auto& r = meshes[k];
      const std::string setting = std::to_string(r.n_major) + "x" + std::to_string(r.n_minor) +
                                  " loop, " + std::to_string(r.n_around) + " around wire (" +
                                  std::to_string(mesh_models[k]->num_triangles()) + " tri)";
      progress.Step(f.name + ": mesh " + std::to_string(r.n_major));
      ns = MedianNsPerQuery(n, std::min(opt.reps, 3), 20,
                            [&](int i) { res[i] = mesh_models[k]->Calc(f.poses[i]); });
      results[fi].push_back(Evaluate("mesh (FCL)", setting, f, res, true, ns));
    }
  }
  progress.Step("quartic check");
  const std::vector<QuarticCheck> qc = RunQuarticCheck(rng, opt.quick ? 200 : 2000);
  progress.Finish();

  std::printf(
      "loop R = %.3g m, r_l = %.3g m; course %zu pieces, %.4g m, r_w = %.3g m; %d queries\n",
      loop.radius_m, loop.wire_radius_m, wire.pieces.size(), model.length_m(), wire.radius_m, n);
  for (std::size_t fi = 0; fi < families.size(); ++fi) {
    int contacts = 0;
    for (const long double c : families[fi].ref_clearance) contacts += c <= 0;
    std::printf("\n%s (%s), %d in contact\n", families[fi].name.c_str(), families[fi].what.c_str(),
                contacts);
    std::printf("%-11s %-42s %12s %12s %12s %8s\n", "method", "setting", "ns/query", "max err m",
                "median err m", "contact");
    for (const Measure& m : results[fi]) {
      std::printf("%-11s %-42s %12.0f %12.2e %12.2e %7.2f%%\n", m.method.c_str(), m.setting.c_str(),
                  m.ns_per_query, m.max_error_m, m.median_error_m, 100 * m.contact_agreement);
    }
  }
  std::printf("\nsegment-circle minimum on near-degenerate segments (R = 1), max |error|:\n");
  std::printf("%-52s %12s %12s\n", "family", "brackets", "quartic.h");
  for (const QuarticCheck& q : qc) {
    std::printf("%-52s %12.2e %12.2e\n", q.family.c_str(), q.brackets_max, q.quartic_max);
  }
  if (!opt.json.empty()) {
    std::ofstream j(opt.json);
    if (!j) {
      std::fprintf(stderr, "microdex-bench loop_wire: cannot write %s\n", opt.json.c_str());
      return 2;
    }
    j << "{\n  \"loop\": {\"radius_m\": " << loop.radius_m
      << ", \"wire_radius_m\": " << loop.wire_radius_m << "},\n";
    j << "  \"course\": {\"pieces\": " << wire.pieces.size()
      << ", \"length_m\": " << model.length_m() << ", \"wire_radius_m\": " << wire.radius_m
      << "},\n";
    j << "  \"queries\": " << n << ",\n  \"families\": [\n";
    char buf[512];
    for (std::size_t fi = 0; fi < families.size(); ++fi) {
      j << "    {\"name\": \"" << families[fi].name << "\", \"what\": \"" << families[fi].what
        << "\", \"methods\": [\n";
      for (std::size_t k = 0; k < results[fi].size(); ++k) {
        const Measure& m = results[fi][k];
        std::snprintf(buf, sizeof(buf),
                      "      {\"method\": \"%s\", \"setting\": \"%s\", \"ns_per_query\": %.1f, "
                      "\"max_error_m\": %.3e, \"median_error_m\": %.3e, \"error_queries\": %d, "
                      "\"contact_agreement\": %.4f}%s\n",
                      m.method.c_str(), m.setting.c_str(), m.ns_per_query,
                      std::isfinite(m.max_error_m) ? m.max_error_m : -1,
                      std::isfinite(m.median_error_m) ? m.median_error_m : -1, m.error_queries,
                      m.contact_agreement, k + 1 < results[fi].size() ? "," : "");
        j << buf;
      }
      j << "    ]}" << (fi + 1 < families.size() ? "," : "") << "\n";
    }
    j << "  ],\n  \"segment_quartic_check\": [\n";
    for (std::size_t k = 0; k < qc.size(); ++k) {
      std::snprintf(buf, sizeof(buf),
                    "    {\"family\": \"%s\", \"cases\": %d, \"brackets_max_error_R\": %.3e, "
                    "\"quartic_max_error_R\": %.3e}%s\n",
                    qc[k].family.c_str(), qc[k].cases, qc[k].brackets_max, qc[k].quartic_max,
                    k + 1 < qc.size() ? "," : "");
      j << buf;
    }
    j << "  ]\n}\n";
  }
  return 0;
}

int RunLoopWire(int argc, char** argv) {
  CLI::App app{"loop along a wire: error vs time of the exact clearance, sampling, FCL meshes"};
  Options opt;
  app.add_option("--json", opt.json, "write the report as JSON");
  app.add_option("--queries", opt.queries, "random poses per family")
      ->check(CLI::Range(10, 1000000));
  app.add_option("--reps", opt.reps, "timing repetitions (median taken)")
      ->check(CLI::Range(1, 100));
  app.add_option("--seed", opt.seed, "random seed of the poses");
  app.add_flag("--quick", opt.quick, "reduced run (200 queries, two sample counts, coarse meshes)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return RunReport(opt);
}

}  // namespace

MICRODEX_REGISTER_BENCH(loop_wire, "loop_wire",
                        "loop along a wire: error vs time of the exact clearance, sampling, FCL "
                        "meshes; the segment quartic check",
                        RunLoopWire);

}  // namespace microdex::bench
