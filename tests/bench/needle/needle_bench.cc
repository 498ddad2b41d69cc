// microdex-bench needle: error against run time of the needle–vessel clearance methods
// (thesis Fig. 4.6), and the --cases validation tool (../shared/DESIGN.md "Needle cases").
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "common/geometry/arc_torus.h"
#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/arc_torus_mesh.h"
#include "common/geometry/arc_torus_sampled.h"
#include "common/geometry/arc_torus_sp.h"

namespace microdex::bench {
namespace {

using geometry::ArcDef;
using geometry::ArcTorusClearance;
using geometry::ClearanceStatus;
using geometry::TorusSegmentDef;

constexpr double kPi = std::numbers::pi;

// ---- --cases -------------------------------------------------------------------------------

constexpr const char* kCasesHeader =
    "nx,ny,nz,nqw,nqx,nqy,nqz,needle_radius,needle_sweep,tx,ty,tz,tqw,tqx,tqy,tqz,R,r,"
    "segment_angle";
constexpr int kCasesColumns = 19;

class BadInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

Eigen::Isometry3d PoseFrom(const double* v, const std::string& where, const char* which) {
  Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  const double n = q.norm();
  if (!(std::abs(n - 1) < 1e-6)) {
    throw BadInput(where + ": " + which + " quaternion is not unit (norm " + std::to_string(n) +
                   ")");
  }
  q.normalize();
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q.toRotationMatrix();
  X.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return X;
}

std::string FormatClearance(const ArcTorusClearance& c) {
  if (c.status != ClearanceStatus::kOk) return "nan";
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", c.clearance_m);
  return buf;
}

int RunCases(const std::string& in_path, const std::string& out_path) {
  std::ifstream in(in_path);
  if (!in) throw BadInput(in_path + ": cannot open");
  std::string line;
  int line_no = 1;
  if (!std::getline(in, line) || Trim(line) != kCasesHeader) {
    throw BadInput(in_path + ":1: expected the header " + std::string(kCasesHeader));
  }
  std::vector<std::string> rows;
  while (std::getline(in, line)) {
    ++line_no;
    if (Trim(line).empty()) continue;
    const std::string where = in_path + ":" + std::to_string(line_no);
    std::vector<double> v;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      const std::string t = Trim(cell);
      char* end = nullptr;
      const double x = std::strtod(t.c_str(), &end);
      if (t.empty() || end != t.c_str() + t.size()) {
        throw BadInput(where + ": column " + std::to_string(v.size() + 1) + " '" + t +
                       "' is not a number");
      }
      v.push_back(x);
    }
    if (static_cast<int>(v.size()) != kCasesColumns) {
      throw BadInput(where + ": expected " + std::to_string(kCasesColumns) + " columns, got " +
                     std::to_string(v.size()));
    }
    ArcDef arc;
    arc.X_WN = PoseFrom(&v[0], where, "needle");
    arc.radius_m = v[7];
    arc.sweep_rad = v[8];
    TorusSegmentDef torus;
    torus.X_WV = PoseFrom(&v[9], where, "tube");
    torus.core_radius_m = v[16];
    torus.tube_radius_m = v[17];
    torus.segment_angle_rad = v[18];
    if (const char* error = geometry::FindArcTorusInputError(arc, torus)) {
      throw BadInput(where + ": " + error);
    }
    const ArcTorusClearance sp = geometry::CalcArcTorusClearanceSP(arc, torus);
    const ArcTorusClearance exact = geometry::CalcArcTorusClearanceExact(arc, torus);
    rows.push_back(FormatClearance(sp) + "," + FormatClearance(exact) + "," +
                   (sp.status == ClearanceStatus::kOk && sp.contact ? "1" : "0") + "," +
                   (exact.status == ClearanceStatus::kOk && exact.contact ? "1" : "0"));
  }
  std::ofstream out(out_path);
  if (!out) throw BadInput(out_path + ": cannot open for writing");
  out << "sp_clearance,exact_clearance,sp_contact,exact_contact\n";
  for (const std::string& r : rows) out << r << '\n';
  if (!out) throw BadInput(out_path + ": write failed");
  return 0;
}

// ---- Error against run time ----------------------------------------------------------------

// The training geometry: tube of core radius 5 mm and radius 0.5 mm (whole torus, so that the
// mesh baseline answers the same question), needle of the same radius over 3/4 of a half turn.
struct Scene {
  ArcDef arc;
  TorusSegmentDef torus;
  std::vector<Eigen::Isometry3d> X_WN;  // one needle pose per query
};

Scene MakeScene(int queries, uint64_t seed) {
  Scene scene;
  scene.torus.core_radius_m = 5e-3;
  scene.torus.tube_radius_m = 0.5e-3;
  scene.torus.segment_angle_rad = 2 * kPi;
  Eigen::Isometry3d X_WV = Eigen::Isometry3d::Identity();
  X_WV.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.5).normalized()).matrix();
  X_WV.translation() = Eigen::Vector3d(0.02, -0.01, 0.03);
  scene.torus.X_WV = X_WV;
  scene.arc.radius_m = 5e-3;
  scene.arc.sweep_rad = 0.75 * kPi;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double R = scene.torus.core_radius_m, r = scene.torus.tube_radius_m;
  for (int i = 0; i < queries; ++i) {
    // On the core circle at a random azimuth, then moved by up to 0.9 r along each axis and
    // turned by up to 0.9 r/R about a random axis: mostly inside the tube, some in contact.
    Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    X_VN.linear() = (Eigen::AngleAxisd(0.9 * r / R * std::abs(u(rng)), axis) *
                     Eigen::AngleAxisd(kPi * u(rng), Eigen::Vector3d::UnitZ()))
                        .matrix();
    X_VN.translation() = 0.9 * r * Eigen::Vector3d(u(rng), u(rng), u(rng));
    scene.X_WN.push_back(X_WV * X_VN);
  }
  return scene;
}

struct MethodResult {
  std::string name, setting;
  double ns_per_query = 0;
  double max_abs_error = 0, rms_error = 0, agreement = 0;
  int error_queries = 0;  // queries the errors are taken over
};

using Clock = std::chrono::steady_clock;

// Median over repetitions of the mean time per query; a repetition is one pass over all
// queries. Slow methods get fewer repetitions (at least 3) within a time budget.
template <typename Fn>
double MedianNsPerQuery(int queries, int reps, double budget_s, Fn&& fn) {
  std::vector<double> per_rep;
  const auto start = Clock::now();
  for (int rep = 0; rep < reps; ++rep) {
    const auto t0 = Clock::now();
    for (int i = 0; i < queries; ++i) fn(i);
    const auto t1 = Clock::now();
    per_rep.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / queries);
    if (rep >= 2 && std::chrono::duration<double>(t1 - start).count() > budget_s) break;
  }
  std::nth_element(per_rep.begin(), per_rep.begin() + per_rep.size() / 2, per_rep.end());
  return per_rep[per_rep.size() / 2];
}

void Score(const std::vector<ArcTorusClearance>& got, const std::vector<ArcTorusClearance>& ref,
           bool errors_only_without_contact, MethodResult* m) {
  double max_e = 0, sum2 = 0;
  int n = 0, agree = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    const bool got_contact = got[i].status == ClearanceStatus::kOk && got[i].contact;
    if (got_contact == ref[i].contact) ++agree;
    if (got[i].status != ClearanceStatus::kOk) continue;
    if (errors_only_without_contact && got_contact) continue;
    const double e = std::abs(got[i].clearance_m - ref[i].clearance_m);
    max_e = std::max(max_e, std::isfinite(e) ? e : std::numeric_limits<double>::infinity());
    sum2 += e * e;
    ++n;
  }
  m->max_abs_error = max_e;
  m->rms_error = n > 0 ? std::sqrt(sum2 / n) : 0;
  m->agreement = static_cast<double>(agree) / got.size();
  m->error_queries = n;
}

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

struct ReportOptions {
  std::string json, csv, plot, mesh_dir;
  bool quick = false;
  int queries = 0, reps = 0;
  uint64_t seed = 1;
};

// The cheapest setting of `name` whose max error is within `tol`; nullptr when none.
const MethodResult* Cheapest(const std::vector<MethodResult>& all, const std::string& name,
                             double tol) {
  const MethodResult* best = nullptr;
  for (const MethodResult& m : all) {
    if (m.name != name || !(m.max_abs_error <= tol)) continue;
    if (best == nullptr || m.ns_per_query < best->ns_per_query) best = &m;
  }
  return best;
}

void WritePlot(const std::vector<MethodResult>& all, const std::string& png) {
  const std::string data = png + ".dat";
  std::ofstream d(data);
  const char* names[] = {"sp", "exact", "sampling", "mesh"};
  for (const char* name : names) {
    d << "# " << name << "\n";
    for (const MethodResult& m : all) {
      if (m.name != name) continue;
      // The exact method is the reference (error 0): drawn at 1e-16 m on the log axis.
      d << m.ns_per_query << ' ' << std::max(m.max_abs_error, 1e-16) << ' '
        << std::max(m.rms_error, 1e-16) << " \"" << m.setting << "\"\n";
    }
    d << "\n\n";
  }
  d.close();
  const std::string script = png + ".gp";
  std::ofstream g(script);
  g << "set terminal pngcairo size 900,640\n"
    << "set output '" << png << "'\n"
    << "set logscale xy\nset grid\n"
    << "set xlabel 'time per query (ns)'\nset ylabel 'max |clearance error| (m)'\n"
    << "set title 'needle-vessel clearance: error against run time'\n"
    << "set key top right\n"
    << "plot '" << data << "' index 0 with linespoints title 'SP (quartic tol / polish)', \\\n"
    << "  '' index 1 with points pt 7 ps 2 title 'exact (reference, error 0)', \\\n"
    << "  '' index 2 with linespoints title 'sampling N=10..10^4', \\\n"
    << "  '' index 3 with linespoints title 'mesh (FCL OBBRSS)'\n";
  g.close();
  const std::string cmd = "gnuplot '" + script + "'";
  if (std::system(cmd.c_str()) != 0) {
    throw std::runtime_error("gnuplot failed on " + script);
  }
}

int RunReport(const ReportOptions& opt) {
  const int queries = opt.queries > 0 ? opt.queries : (opt.quick ? 200 : 2000);
  const int reps = opt.reps > 0 ? opt.reps : (opt.quick ? 3 : 7);
  const double budget_s = opt.quick ? 0.5 : 4.0;
  const Scene scene = MakeScene(queries, opt.seed);
  const TorusSegmentDef& torus = scene.torus;
  const double r = torus.tube_radius_m;
  std::vector<ArcTorusClearance> exact(queries);
  for (int i = 0; i < queries; ++i) {
    ArcDef arc = scene.arc;
    arc.X_WN = scene.X_WN[i];
    exact[i] = geometry::CalcArcTorusClearanceExact(arc, torus);
    if (exact[i].status != ClearanceStatus::kOk) {
      throw std::runtime_error("exact method failed on benchmark query " + std::to_string(i));
    }
  }
  std::vector<MethodResult> all;
  std::vector<ArcTorusClearance> got(queries);
  volatile double sink = 0;

  auto run_analytic = [&](const std::string& name, const std::string& setting, auto&& calc) {
    MethodResult m{name, setting};
    m.ns_per_query = MedianNsPerQuery(queries, reps, budget_s, [&](int i) {
      ArcDef arc = scene.arc;
      arc.X_WN = scene.X_WN[i];
      got[i] = calc(arc);
      sink = sink + got[i].clearance_m;
    });
    Score(got, exact, false, &m);
    all.push_back(m);
    std::fprintf(stderr, "  %-9s %-26s %12.1f ns  max err %.3g m\n", name.c_str(), setting.c_str(),
                 m.ns_per_query, m.max_abs_error);
  };

  struct SpSetting {
    const char* label;
    double quartic_tol;
    int polish;
  };
  const SpSetting sp_settings[] = {{"tol=1e-3,polish=0", 1e-3, 0},
                                   {"tol=1e-6,polish=0", 1e-6, 0},
                                   {"tol=1e-10,polish=0", 1e-10, 0},
                                   {"tol=1e-15,polish=0", 1e-15, 0},
                                   {"tol=1e-15,polish=12 (default)", 1e-15, 12}};
  for (const SpSetting& s : sp_settings) {
    geometry::SpOptions options;
    options.quartic_tol = s.quartic_tol;
    options.polish_max_iters = s.polish;
    run_analytic("sp", s.label, [&](const ArcDef& arc) {
      return geometry::CalcArcTorusClearanceSP(arc, torus, options);
    });
  }
  run_analytic("exact", "closed form",
               [&](const ArcDef& arc) { return geometry::CalcArcTorusClearanceExact(arc, torus); });
  for (int n : {10, 30, 100, 300, 1000, 3000, 10000}) {
    run_analytic("sampling", "N=" + std::to_string(n), [&](const ArcDef& arc) {
      return geometry::CalcArcTorusClearanceSampled(arc, torus, n);
    });
  }
  std::vector<geometry::MeshResolution> resolutions = {
      {16, 32, 8}, {32, 64, 16}, {64, 128, 32}, {128, 256, 64}, {256, 512, 128}};
  if (opt.quick) resolutions.resize(3);
  for (const geometry::MeshResolution& res : resolutions) {
    const geometry::ArcTorusMeshModel model(scene.arc, torus, res, opt.mesh_dir);
    const std::string setting = "needle " + std::to_string(res.needle_segments) + ", wall " +
                                std::to_string(res.n_major) + "x" + std::to_string(res.n_minor);
    MethodResult m{"mesh", setting};
    m.ns_per_query = MedianNsPerQuery(queries, reps, budget_s, [&](int i) {
      got[i] = model.Calc(scene.X_WN[i], torus.X_WV);
      sink = sink + got[i].clearance_m;
    });
    Score(got, exact, true, &m);
    all.push_back(m);
    std::fprintf(stderr, "  %-9s %-26s %12.1f ns  max err %.3g m (over %d no-contact)\n", "mesh",
                 setting.c_str(), m.ns_per_query, m.max_abs_error, m.error_queries);
  }

  // Ratios: cheapest setting within 1e-3·r against the SP default (the most accurate SP
  // setting).
  const double tol = 1e-3 * r;
  const MethodResult* sp = nullptr;
  for (const MethodResult& m : all) {
    if (m.name == "sp" && m.setting.find("default") != std::string::npos) sp = &m;
  }
  auto ratio = [&](const char* name) {
    const MethodResult* m = Cheapest(all, name, tol);
    return m == nullptr ? std::numeric_limits<double>::quiet_NaN()
                        : m->ns_per_query / sp->ns_per_query;
  };
  const double mesh_over_sp = ratio("mesh");
  const double sampling_over_sp = ratio("sampling");
  const double exact_over_sp = ratio("exact");
  int contacts = 0;
  for (const ArcTorusClearance& e : exact) contacts += e.contact;

  if (!opt.json.empty()) {
    std::ofstream j(opt.json);
    if (!j) throw BadInput(opt.json + ": cannot open for writing");
    j << "{\n  \"queries\": " << queries << ",\n  \"contacts\": " << contacts
      << ",\n  \"repetitions\": " << reps << ",\n  \"tube_radius_m\": " << JsonNumber(r)
      << ",\n  \"error_tolerance_m\": " << JsonNumber(tol) << ",\n  \"sp_reference_setting\": \""
      << sp->setting << "\",\n  \"methods\": [\n";
    for (size_t i = 0; i < all.size(); ++i) {
      const MethodResult& m = all[i];
      j << "    {\"name\": \"" << m.name << "\", \"setting\": \"" << m.setting
        << "\", \"ns_per_query\": " << JsonNumber(m.ns_per_query)
        << ", \"max_abs_error\": " << JsonNumber(m.max_abs_error)
        << ", \"rms_error\": " << JsonNumber(m.rms_error)
        << ", \"agreement\": " << JsonNumber(m.agreement)
        << ", \"error_queries\": " << m.error_queries << "}" << (i + 1 < all.size() ? "," : "")
        << "\n";
    }
    j << "  ],\n  \"ratios\": {\"mesh_over_sp\": " << JsonNumber(mesh_over_sp)
      << ", \"sampling_over_sp\": " << JsonNumber(sampling_over_sp)
      << ", \"exact_over_sp\": " << JsonNumber(exact_over_sp) << "},\n"
      << "  \"sp_queries_per_second\": " << JsonNumber(1e9 / sp->ns_per_query) << "\n}\n";
  }
  if (!opt.csv.empty()) {
    std::ofstream c(opt.csv);
    if (!c) throw BadInput(opt.csv + ": cannot open for writing");
    c << "name,setting,ns_per_query,max_abs_error,rms_error,agreement,error_queries\n";
    for (const MethodResult& m : all) {
      c << m.name << ",\"" << m.setting << "\"," << m.ns_per_query << ',' << m.max_abs_error << ','
        << m.rms_error << ',' << m.agreement << ',' << m.error_queries << '\n';
    }
  }
  if (!opt.plot.empty()) WritePlot(all, opt.plot);
  std::printf("needle: %d queries (%d in contact); SP reference: %s, %.1f ns/query (%.3g/s)\n",
              queries, contacts, sp->setting.c_str(), sp->ns_per_query, 1e9 / sp->ns_per_query);
  std::printf("ratios within %.3g m: mesh/sp %.4g, sampling/sp %.4g, exact/sp %.4g\n", tol,
              mesh_over_sp, sampling_over_sp, exact_over_sp);
  return 0;
}

int RunNeedle(int argc, char** argv) {
  CLI::App app{"needle-vessel clearance: error against run time, or --cases validation"};
  ReportOptions opt;
  std::string cases, out;
  opt.mesh_dir = "assets/meshes";
  app.add_option("--json", opt.json, "write the report as JSON");
  app.add_option("--csv", opt.csv, "write the table as CSV");
  app.add_option("--plot", opt.plot, "write error (log) against time (log) as PNG (gnuplot)");
  app.add_flag("--quick", opt.quick, "reduced run (200 queries, coarse meshes only)");
  app.add_option("--queries", opt.queries, "number of random needle poses");
  app.add_option("--reps", opt.reps, "timing repetitions (median taken)");
  app.add_option("--seed", opt.seed, "random seed of the poses");
  app.add_option("--mesh-dir", opt.mesh_dir, "where the OBJ meshes are read / generated");
  app.add_option("--cases", cases, "evaluate the cases of this CSV (DESIGN.md columns)");
  app.add_option("--out", out, "output CSV of --cases");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (!cases.empty() || !out.empty()) {
      if (cases.empty() || out.empty()) throw BadInput("--cases and --out go together");
      return RunCases(cases, out);
    }
    if (opt.json.empty() && opt.csv.empty() && opt.plot.empty()) {
      throw BadInput("nothing to do: give --json, --csv, --plot, or --cases with --out");
    }
    return RunReport(opt);
  } catch (const BadInput& e) {
    std::fprintf(stderr, "microdex-bench needle: %s\n", e.what());
    return 2;
  }
}

}  // namespace

MICRODEX_REGISTER_BENCH(needle, "needle",
                        "needle-vessel clearance: error vs time of SP, exact, sampling, mesh; "
                        "--cases validation",
                        RunNeedle);

}  // namespace microdex::bench
