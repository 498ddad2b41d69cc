// microdex-bench needle: error against run time of the needle–vessel clearance methods
// (thesis Fig. 4.6), and the --cases validation tool (README.md "Needle cases CSV").
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
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
#include "bench_util.h"
#include "common/base/json_text.h"
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

// One needle–vessel query.
struct Query {
  ArcDef arc;
  TorusSegmentDef torus;
};

// A family of queries: what the station asks in one situation. The mesh baseline answers
// only where the geometry is fixed and the tube is a whole torus (its wall mesh has no notion
// of the azimuth range, README.md).
struct Family {
  std::string name, description;
  std::vector<Query> queries;
  bool mesh = false;
};

Eigen::Isometry3d TrainingVesselPose() {
  Eigen::Isometry3d X_WV = Eigen::Isometry3d::Identity();
  X_WV.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.5).normalized()).matrix();
  X_WV.translation() = Eigen::Vector3d(0.02, -0.01, 0.03);
  return X_WV;
}

// The training geometry: tube of core radius 5 mm and radius 0.5 mm, needle of the same
// radius over 3/4 of a half turn. The needle starts on the core circle at an azimuth drawn from
// [azimuth_lo, azimuth_hi], then is moved by up to 0.9 r along each axis and turned by up to
// 0.9 r/R about a random axis: mostly inside the tube, some in contact.
Family MakeTrainingFamily(const std::string& name, double segment_angle, double azimuth_lo,
                          double azimuth_hi, int queries, std::mt19937_64& rng) {
  Family family;
  family.name = name;
  Query q;
  q.torus.core_radius_m = 5e-3;
  q.torus.tube_radius_m = 0.5e-3;
  q.torus.segment_angle_rad = segment_angle;
  q.torus.X_WV = TrainingVesselPose();
  q.arc.radius_m = 5e-3;
  q.arc.sweep_rad = 0.75 * kPi;
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  const double R = q.torus.core_radius_m, r = q.torus.tube_radius_m;
  while (static_cast<int>(family.queries.size()) < queries) {
    Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double azimuth = azimuth_lo + (azimuth_hi - azimuth_lo) * unit(rng);
    X_VN.linear() = (Eigen::AngleAxisd(0.9 * r / R * std::abs(u(rng)), axis) *
                     Eigen::AngleAxisd(azimuth, Eigen::Vector3d::UnitZ()))
                        .matrix();
    X_VN.translation() = 0.9 * r * Eigen::Vector3d(u(rng), u(rng), u(rng));
    q.arc.X_WN = q.torus.X_WV * X_VN;
    if (geometry::CalcArcTorusClearanceExact(q.arc, q.torus).status == ClearanceStatus::kOk) {
      family.queries.push_back(q);
    }
  }
  return family;
}

// Needles through the wall: through a random point 0.7–1.3 r from the core circle inside the
// range, in a random direction, ρ = 0.2–1.7 R, any sweep; half of the tubes are segments.
Family MakeCrossingFamily(int queries, std::mt19937_64& rng) {
  Family family;
  family.name = "crossing the wall";
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n;
  while (static_cast<int>(family.queries.size()) < queries) {
    Query q;
    q.torus.core_radius_m = 5e-3;
    q.torus.tube_radius_m = 0.5e-3;
    q.torus.segment_angle_rad = u(rng) < 0.5 ? 2 * kPi : 0.3 + (2 * kPi - 0.3) * u(rng);
    q.torus.X_WV = TrainingVesselPose();
    const double R = q.torus.core_radius_m, r = q.torus.tube_radius_m;
    q.arc.radius_m = R * (0.2 + 1.5 * u(rng));
    q.arc.sweep_rad = 0.05 + (2 * kPi - 0.05) * u(rng);
    const double phi = q.torus.segment_angle_rad * u(rng), psi = 2 * kPi * u(rng);
    const double rr = r * (0.7 + 0.6 * u(rng));
    const Eigen::Vector3d p_V((R + rr * std::cos(psi)) * std::cos(phi),
                              (R + rr * std::cos(psi)) * std::sin(phi), rr * std::sin(psi));
    const Eigen::Matrix3d R_VN =
        Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    const double s0 = q.arc.sweep_rad * u(rng);
    Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
    X_VN.linear() = R_VN;
    X_VN.translation() = p_V - R_VN * Eigen::Vector3d(q.arc.radius_m * std::cos(s0),
                                                      q.arc.radius_m * std::sin(s0), 0);
    q.arc.X_WN = q.torus.X_WV * X_VN;
    if (geometry::CalcArcTorusClearanceExact(q.arc, q.torus).status == ClearanceStatus::kOk) {
      family.queries.push_back(q);
    }
  }
  return family;
}

// The pose range SP handles: r/R 0.05–0.5, ρ/R log-uniform in [0.1, 10], the needle centre
// anywhere within 3(R + ρ) of the vessel, any orientation and sweep; half segments. Mostly
// far from the tube (deep contacts): the exact method answers those inside SP.
Family MakeWideFamily(int queries, std::mt19937_64& rng) {
  Family family;
  family.name = "wide poses";
  std::uniform_real_distribution<double> u(0, 1), v(-1, 1);
  std::normal_distribution<double> n;
  while (static_cast<int>(family.queries.size()) < queries) {
    Query q;
    const double R = 5e-3;
    q.torus.core_radius_m = R;
    q.torus.tube_radius_m = R * (0.05 + 0.45 * u(rng));
    q.torus.segment_angle_rad = u(rng) < 0.5 ? 2 * kPi : 0.1 + (2 * kPi - 0.1) * u(rng);
    q.torus.X_WV = TrainingVesselPose();
    q.arc.radius_m = R * std::pow(10.0, -1 + 2 * u(rng));
    q.arc.sweep_rad = 2 * kPi * (0.01 + 0.99 * u(rng));
    Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
    X_VN.linear() =
        Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    X_VN.translation() = 3 * (R + q.arc.radius_m) * Eigen::Vector3d(v(rng), v(rng), v(rng));
    q.arc.X_WN = q.torus.X_WV * X_VN;
    if (geometry::CalcArcTorusClearanceExact(q.arc, q.torus).status == ClearanceStatus::kOk) {
      family.queries.push_back(q);
    }
  }
  return family;
}

std::vector<Family> MakeFamilies(int queries, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Family> families;
  families.push_back(MakeTrainingFamily("training, whole torus", 2 * kPi, -kPi, kPi, queries, rng));
  families.back().mesh = true;
  families.back().description =
      "needle on the core circle at any azimuth, moved by <= 0.9 r, turned by <= 0.9 r/R";
  // The station's scenario: the needle moved along a curved segment (Ω = π/2), entering and
  // leaving it, so the clipping (§4.2.4) acts on nearly every query.
  families.push_back(MakeTrainingFamily("training, along a segment", kPi / 2, -0.75 * kPi + 0.1,
                                        kPi / 2 - 0.1, queries, rng));
  families.back().description =
      "segment Ω = π/2; needle starting anywhere from 3π/4 before it to its end, same moves";
  families.push_back(MakeCrossingFamily(queries, rng));
  families.back().description =
      "through a point 0.7-1.3 r from the core, random direction, ρ 0.2-1.7 R, any sweep";
  families.push_back(MakeWideFamily(queries, rng));
  families.back().description =
      "r/R 0.05-0.5, ρ/R 0.1-10, centre within 3(R + ρ), any orientation and sweep";
  return families;
}

struct MethodResult {
  std::string name, setting;
  double ns_per_query = 0;
  double max_abs_error = 0, rms_error = 0, agreement = 0;
  int error_queries = 0;  // queries the errors are taken over
  // Distance of the method's deepest needle point from the exact one, over the queries whose
  // deepest point is well defined (IsolatedMinimum); NaN when the method gives none.
  double max_point_error = 0;
  int point_queries = 0;
};

using Clock = std::chrono::steady_clock;

// Whether the exact deepest point of a query is well defined: every needle point inside the
// segment farther than `radius_m` (along the needle) from it is shallower by more than
// `margin_m`. Checked on a dense grid of the needle (its own clearance, computed here from the
// definition). Where it fails (the needle runs nearly parallel to the wall, as on the ideal
// path), any point of a long stretch is "deepest" and a point error means nothing.
bool IsolatedMinimum(const Query& q, const ArcTorusClearance& exact, double radius_m,
                     double margin_m) {
  constexpr int kGrid = 4000;
  const Eigen::Isometry3d X_VN = q.torus.X_WV.inverse() * q.arc.X_WN;
  const double R = q.torus.core_radius_m, r = q.torus.tube_radius_m, rho = q.arc.radius_m;
  for (int k = 0; k <= kGrid; ++k) {
    const double s = q.arc.sweep_rad * k / kGrid;
    if (rho * std::abs(s - exact.s_rad) <= radius_m) continue;
    const Eigen::Vector3d p = X_VN * Eigen::Vector3d(rho * std::cos(s), rho * std::sin(s), 0);
    if (!geometry::IsAzimuthInSegment(p.x(), p.y(), q.torus.segment_angle_rad)) continue;
    const double c = r - std::hypot(std::hypot(p.x(), p.y()) - R, p.z());
    if (c <= exact.clearance_m + margin_m) return false;
  }
  return true;
}

void Score(const std::vector<ArcTorusClearance>& got, const std::vector<ArcTorusClearance>& ref,
           const std::vector<char>& isolated, bool errors_only_without_contact, MethodResult* m) {
  double max_e = 0, sum2 = 0, max_p = 0;
  int n = 0, agree = 0, np = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    const bool got_contact = got[i].status == ClearanceStatus::kOk && got[i].contact;
    if (got_contact == ref[i].contact) ++agree;
    if (got[i].status != ClearanceStatus::kOk) continue;
    if (errors_only_without_contact && got_contact) continue;
    const double e = std::abs(got[i].clearance_m - ref[i].clearance_m);
    max_e = std::max(max_e, std::isfinite(e) ? e : std::numeric_limits<double>::infinity());
    sum2 += e * e;
    ++n;
    if (isolated[i]) {
      const double pe = (got[i].p_WD - ref[i].p_WD).norm();
      max_p = std::max(max_p, std::isfinite(pe) ? pe : std::numeric_limits<double>::infinity());
      ++np;
    }
  }
  m->max_abs_error = max_e;
  m->max_point_error = max_p;
  m->point_queries = np;
  m->rms_error = n > 0 ? std::sqrt(sum2 / n) : 0;
  m->agreement = static_cast<double>(agree) / got.size();
  m->error_queries = n;
}

using ::microdex::JsonNumber;

struct ReportOptions {
  std::string json, csv, plot, mesh_dir;
  bool quick = false;
  int queries = 0, reps = 0;
  uint64_t seed = 1;
};

// The cheapest setting of `name` whose max error is within `tol` (and, with `point`, whose
// deepest point is also within `tol` of the exact one); nullptr when none.
const MethodResult* Cheapest(const std::vector<MethodResult>& all, const std::string& name,
                             double tol, bool point = false) {
  const MethodResult* best = nullptr;
  for (const MethodResult& m : all) {
    if (m.name != name || !(m.max_abs_error <= tol)) continue;
    if (point && !(m.max_point_error <= tol)) continue;
    if (best == nullptr || m.ns_per_query < best->ns_per_query) best = &m;
  }
  return best;
}

void WritePlot(const std::vector<MethodResult>& all, const std::string& png,
               const std::string& family) {
  const std::string data = png + ".dat";
  std::ofstream d(data);
  const char* names[] = {"sp", "exact", "sampling", "mesh", "sampling_clipped", "sp_thesis"};
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
    << "set title 'needle-vessel clearance: error against run time (" << family << ")'\n"
    << "set key top right\n"
    << "plot '" << data << "' index 0 with points pt 9 ps 2 title 'SP staged (default)', \\\n"
    << "  '' index 1 with points pt 7 ps 2 title 'exact (reference, error 0)', \\\n"
    << "  '' index 2 with linespoints title 'sampling N=10..10^4', \\\n"
    << "  '' index 3 with linespoints title 'mesh (FCL OBBRSS)', \\\n"
    << "  '' index 4 with linespoints title 'sampling over the clipped pieces', \\\n"
    << "  '' index 5 with linespoints title 'SP thesis pass (quartic tol)'\n";
  g.close();
  const std::string cmd = "gnuplot '" + script + "'";
  if (std::system(cmd.c_str()) != 0) {
    throw std::runtime_error("gnuplot failed on " + script);
  }
}

struct Ratios {
  double mesh_over_sp = std::numeric_limits<double>::quiet_NaN();
  double sampling_over_sp = std::numeric_limits<double>::quiet_NaN();
  double exact_over_sp = std::numeric_limits<double>::quiet_NaN();
  // The sampling baseline over the clipped pieces, ends included (arc_torus_sampled.h).
  double sampling_clipped_over_sp = std::numeric_limits<double>::quiet_NaN();
  // The cheapest settings within the tolerance.
  std::string sampling_setting, sampling_clipped_setting, mesh_setting;
  // The same ratios when the deepest needle point must be within the tolerance too (what the
  // visual and haptic cues use), over the queries where that point is well defined.
  double mesh_over_sp_point = std::numeric_limits<double>::quiet_NaN();
  double sampling_over_sp_point = std::numeric_limits<double>::quiet_NaN();
  double sampling_clipped_over_sp_point = std::numeric_limits<double>::quiet_NaN();
  std::string sampling_point_setting, sampling_clipped_point_setting, mesh_point_setting;
  // Methods whose ratio is a lower bound (no setting within the tolerance).
  std::vector<std::string> lower_bounds;
};

struct FamilyResult {
  const Family* family = nullptr;
  int contacts = 0;
  int isolated = 0;               // queries with a well-defined deepest point
  double tol = 0;                 // 1e-3·r (the smallest r of the family)
  std::vector<MethodResult> all;  // every method and setting
  const MethodResult* sp = nullptr;
  Ratios ratios;
  // Which stage settled each query of the SP default (SpDiagnostics::decision), and how many
  // queries started the ascent from uniform points (the lifted circle unusable).
  std::array<int, 8> decisions{};
  int uniform_starts = 0;
  int lifted_passes = 0;  // queries that ran at least one lifted certificate pass
};

constexpr geometry::SpDecision kDecisions[] = {
    geometry::SpDecision::kInvalidInput,      geometry::SpDecision::kEmptyRange,
    geometry::SpDecision::kThesisPass,        geometry::SpDecision::kQuickCertificate,
    geometry::SpDecision::kLiftedCertificate, geometry::SpDecision::kAlongNeedle,
    geometry::SpDecision::kRoundsExhausted,   geometry::SpDecision::kExact};

FamilyResult RunFamily(const Family& family, const ReportOptions& opt, int reps, double budget_s) {
  FamilyResult fr;
  fr.family = &family;
  const int queries = static_cast<int>(family.queries.size());
  double r_min = std::numeric_limits<double>::infinity();
  for (const Query& q : family.queries) r_min = std::min(r_min, q.torus.tube_radius_m);
  fr.tol = 1e-3 * r_min;
  std::vector<ArcTorusClearance> exact(queries);
  for (int i = 0; i < queries; ++i) {
    exact[i] = geometry::CalcArcTorusClearanceExact(family.queries[i].arc, family.queries[i].torus);
    if (exact[i].status != ClearanceStatus::kOk) {
      throw std::runtime_error("exact method failed on benchmark query " + std::to_string(i));
    }
    fr.contacts += exact[i].contact;
  }
  std::vector<char> isolated(queries);
  for (int i = 0; i < queries; ++i) {
    isolated[i] = IsolatedMinimum(family.queries[i], exact[i], 0.05 * r_min, fr.tol);
    fr.isolated += isolated[i];
  }
  std::vector<ArcTorusClearance> got(queries);
  volatile double sink = 0;
  std::fprintf(stderr, "%s (%d queries, %d in contact)\n", family.name.c_str(), queries,
               fr.contacts);
  auto run_analytic = [&](const std::string& name, const std::string& setting, auto&& calc) {
    MethodResult m{name, setting};
    m.ns_per_query = MedianNsPerQuery(queries, reps, budget_s, [&](int i) {
      got[i] = calc(family.queries[i]);
      sink = sink + got[i].clearance_m;
    });
    Score(got, exact, isolated, false, &m);
    fr.all.push_back(m);
    std::fprintf(stderr, "  %-9s %-30s %12.1f ns  max err %.3g m  point %.3g m\n", name.c_str(),
                 setting.c_str(), m.ns_per_query, m.max_abs_error, m.max_point_error);
  };
  // The thesis's SP pass alone (§4.2–4.3): lift, quartic (4.26) to the given tolerance, the
  // clearance at the extrema of G (no ascent, no certificate).
  for (const double tol : {1e-3, 1e-6, 1e-10, 1e-15}) {
    geometry::SpOptions options;
    options.quartic_tol = tol;
    options.polish_max_iters = 0;
    char label[32];
    std::snprintf(label, sizeof label, "tol=%g", tol);
    run_analytic("sp_thesis", label, [&](const Query& q) {
      return geometry::CalcArcTorusClearanceSP(q.arc, q.torus, options);
    });
  }
  // The default path: clip, distance ascent, level-torus certificate (quick test; lifted SP
  // pass where it cannot prove), exact method for the deep contacts it cannot certify.
  run_analytic("sp", "clip+ascent+certificate (default)",
               [&](const Query& q) { return geometry::CalcArcTorusClearanceSP(q.arc, q.torus); });
  for (const Query& q : family.queries) {
    geometry::SpDiagnostics d;
    geometry::CalcArcTorusClearanceSP(q.arc, q.torus, {}, &d);
    ++fr.decisions[static_cast<int>(d.decision)];
    fr.uniform_starts += d.fallback;
    fr.lifted_passes += d.certify_lifted > 0;
  }
  run_analytic("exact", "closed form", [&](const Query& q) {
    return geometry::CalcArcTorusClearanceExact(q.arc, q.torus);
  });
  for (int n : {10, 30, 100, 300, 1000, 3000, 10000}) {
    run_analytic("sampling", "N=" + std::to_string(n), [&](const Query& q) {
      return geometry::CalcArcTorusClearanceSampled(q.arc, q.torus, n);
    });
  }
  for (int n : {10, 30, 100, 300, 1000, 3000, 10000}) {
    run_analytic("sampling_clipped", "N=" + std::to_string(n), [&](const Query& q) {
      return geometry::CalcArcTorusClearanceSampledClipped(q.arc, q.torus, n);
    });
  }
  if (family.mesh) {
    std::vector<geometry::MeshResolution> resolutions = {
        {16, 32, 8}, {32, 64, 16}, {64, 128, 32}, {128, 256, 64}, {256, 512, 128}};
    if (opt.quick) resolutions.resize(3);
    const Query& q0 = family.queries.front();
    for (const geometry::MeshResolution& res : resolutions) {
      const geometry::ArcTorusMeshModel model(q0.arc, q0.torus, res, opt.mesh_dir);
      const std::string setting = "needle " + std::to_string(res.needle_segments) + ", wall " +
                                  std::to_string(res.n_major) + "x" + std::to_string(res.n_minor);
      MethodResult m{"mesh", setting};
      m.ns_per_query = MedianNsPerQuery(queries, reps, budget_s, [&](int i) {
        got[i] = model.Calc(family.queries[i].arc.X_WN, family.queries[i].torus.X_WV);
        sink = sink + got[i].clearance_m;
      });
      Score(got, exact, isolated, true, &m);
      fr.all.push_back(m);
      std::fprintf(stderr,
                   "  %-9s %-30s %12.1f ns  max err %.3g m  point %.3g m (over %d no-contact)\n",
                   "mesh", setting.c_str(), m.ns_per_query, m.max_abs_error, m.max_point_error,
                   m.error_queries);
    }
  }
  // Ratios: cheapest setting within 1e-3·r against the SP default (its most accurate setting).
  for (const MethodResult& m : fr.all) {
    if (m.name == "sp" && m.setting.find("default") != std::string::npos) fr.sp = &m;
  }
  // When no sampling setting reaches the tolerance, the N that would reach it costs more than the
  // largest N tried (the cost grows with N), so the ratio is reported as that lower bound and
  // listed in `lower_bounds`. Not for the mesh: its cost is not monotonic in the resolution
  // (the BVH's shape matters), so "none" stays NaN there.
  auto ratio = [&](const char* name, std::string* setting, bool point = false) {
    const MethodResult* m = Cheapest(fr.all, name, fr.tol, point);
    if (m == nullptr) {
      const MethodResult* costliest = nullptr;
      for (const MethodResult& c : fr.all) {
        if (c.name == name && (costliest == nullptr || c.ns_per_query > costliest->ns_per_query)) {
          costliest = &c;
        }
      }
      if (costliest == nullptr || std::string(name).rfind("sampling", 0) != 0) {
        return std::numeric_limits<double>::quiet_NaN();
      }
      if (setting != nullptr) *setting = "none within tolerance: > " + costliest->setting;
      fr.ratios.lower_bounds.push_back(std::string(name) + (point ? " (point)" : ""));
      return costliest->ns_per_query / fr.sp->ns_per_query;
    }
    if (setting != nullptr) *setting = m->setting;
    return m->ns_per_query / fr.sp->ns_per_query;
  };
  fr.ratios.mesh_over_sp = ratio("mesh", &fr.ratios.mesh_setting);
  fr.ratios.sampling_over_sp = ratio("sampling", &fr.ratios.sampling_setting);
  fr.ratios.exact_over_sp = ratio("exact", nullptr);
  fr.ratios.sampling_clipped_over_sp =
      ratio("sampling_clipped", &fr.ratios.sampling_clipped_setting);
  fr.ratios.mesh_over_sp_point = ratio("mesh", &fr.ratios.mesh_point_setting, true);
  fr.ratios.sampling_over_sp_point = ratio("sampling", &fr.ratios.sampling_point_setting, true);
  fr.ratios.sampling_clipped_over_sp_point =
      ratio("sampling_clipped", &fr.ratios.sampling_clipped_point_setting, true);
  return fr;
}

void WriteMethodsJson(std::ostream& j, const std::vector<MethodResult>& all, const char* indent) {
  for (size_t i = 0; i < all.size(); ++i) {
    const MethodResult& m = all[i];
    j << indent << "{\"name\": \"" << m.name << "\", \"setting\": \"" << m.setting
      << "\", \"ns_per_query\": " << JsonNumber(m.ns_per_query)
      << ", \"max_abs_error\": " << JsonNumber(m.max_abs_error)
      << ", \"rms_error\": " << JsonNumber(m.rms_error)
      << ", \"agreement\": " << JsonNumber(m.agreement)
      << ", \"error_queries\": " << m.error_queries
      << ", \"max_point_error\": " << JsonNumber(m.max_point_error)
      << ", \"point_queries\": " << m.point_queries << "}" << (i + 1 < all.size() ? "," : "")
      << "\n";
  }
}

std::string RatiosJson(const Ratios& r) {
  return "{\"mesh_over_sp\": " + JsonNumber(r.mesh_over_sp) +
         ", \"sampling_over_sp\": " + JsonNumber(r.sampling_over_sp) +
         ", \"exact_over_sp\": " + JsonNumber(r.exact_over_sp) + "}";
}

// The issue's goals, checked on one family's figures.
struct Goal {
  std::string what;
  double value;
  bool met;
};

std::vector<Goal> CheckGoals(const FamilyResult& fr) {
  const Ratios& r = fr.ratios;
  std::vector<Goal> goals;
  const double qps = 1e9 / fr.sp->ns_per_query;
  goals.push_back({"SP default >= 2e6 queries/s on one core", qps, qps >= 2e6});
  if (fr.family->mesh) {
    goals.push_back({"mesh_over_sp >= 300", r.mesh_over_sp, r.mesh_over_sp >= 300});
  }
  const bool bound =
      std::find(r.lower_bounds.begin(), r.lower_bounds.end(), "sampling") != r.lower_bounds.end();
  goals.push_back({bound ? "sampling_over_sp >= 30 (value: lower bound)" : "sampling_over_sp >= 30",
                   r.sampling_over_sp, r.sampling_over_sp >= 30});
  goals.push_back({"exact_over_sp <= 5", r.exact_over_sp, r.exact_over_sp <= 5});
  return goals;
}

int RunReport(const ReportOptions& opt) {
  const int queries = opt.queries > 0 ? opt.queries : (opt.quick ? 200 : 2000);
  const int reps = opt.reps > 0 ? opt.reps : (opt.quick ? 3 : 7);
  const double budget_s = opt.quick ? 0.5 : 4.0;
  const std::vector<Family> families = MakeFamilies(queries, opt.seed);
  std::vector<FamilyResult> results;
  for (const Family& family : families) results.push_back(RunFamily(family, opt, reps, budget_s));
  // The headline figures are the first family's (the one the mesh baseline can answer).
  const FamilyResult& head = results.front();

  if (!opt.json.empty()) {
    std::ofstream j(opt.json);
    if (!j) throw BadInput(opt.json + ": cannot open for writing");
    j << "{\n  \"family\": \"" << head.family->name << "\",\n  \"queries\": " << queries
      << ",\n  \"contacts\": " << head.contacts << ",\n  \"repetitions\": " << reps
      << ",\n  \"error_tolerance_m\": " << JsonNumber(head.tol)
      << ",\n  \"sp_reference_setting\": \"" << head.sp->setting << "\",\n  \"methods\": [\n";
    WriteMethodsJson(j, head.all, "    ");
    j << "  ],\n  \"ratios\": " << RatiosJson(head.ratios) << ",\n"
      << "  \"sp_queries_per_second\": " << JsonNumber(1e9 / head.sp->ns_per_query) << ",\n"
      << "  \"families\": [\n";
    for (size_t f = 0; f < results.size(); ++f) {
      const FamilyResult& fr = results[f];
      j << "    {\"name\": \"" << fr.family->name << "\", \"description\": \""
        << fr.family->description << "\", \"queries\": " << fr.family->queries.size()
        << ", \"contacts\": " << fr.contacts << ", \"error_tolerance_m\": " << JsonNumber(fr.tol)
        << ",\n     \"ratios\": " << RatiosJson(fr.ratios)
        << ", \"sampling_clipped_over_sp\": " << JsonNumber(fr.ratios.sampling_clipped_over_sp)
        << ", \"cheapest_sampling\": \"" << fr.ratios.sampling_setting
        << "\", \"cheapest_sampling_clipped\": \"" << fr.ratios.sampling_clipped_setting
        << "\", \"cheapest_mesh\": \"" << fr.ratios.mesh_setting << "\",\n     \"lower_bounds\": [";
      for (size_t k = 0; k < fr.ratios.lower_bounds.size(); ++k) {
        j << (k > 0 ? ", " : "") << "\"" << fr.ratios.lower_bounds[k] << "\"";
      }
      j << "], \"isolated_queries\": " << fr.isolated
        << ", \"point_ratios\": {\"mesh_over_sp\": " << JsonNumber(fr.ratios.mesh_over_sp_point)
        << ", \"sampling_over_sp\": " << JsonNumber(fr.ratios.sampling_over_sp_point)
        << ", \"sampling_clipped_over_sp\": "
        << JsonNumber(fr.ratios.sampling_clipped_over_sp_point)
        << "}, \"cheapest_sampling_point\": \"" << fr.ratios.sampling_point_setting
        << "\", \"sp_queries_per_second\": " << JsonNumber(1e9 / fr.sp->ns_per_query)
        << ",\n     \"sp_decisions\": {";
      for (size_t k = 0; k < std::size(kDecisions); ++k) {
        j << (k > 0 ? ", " : "") << "\"" << geometry::ToString(kDecisions[k])
          << "\": " << fr.decisions[static_cast<int>(kDecisions[k])];
      }
      j << "}, \"sp_uniform_starts\": " << fr.uniform_starts
        << ", \"sp_lifted_passes\": " << fr.lifted_passes << ",\n     \"goals\": [";
      const std::vector<Goal> goals = CheckGoals(fr);
      for (size_t g = 0; g < goals.size(); ++g) {
        j << (g > 0 ? ", " : "") << "{\"goal\": \"" << goals[g].what
          << "\", \"value\": " << JsonNumber(goals[g].value)
          << ", \"met\": " << (goals[g].met ? "true" : "false") << "}";
      }
      j << "],\n     \"family_methods\": [\n";
      WriteMethodsJson(j, fr.all, "       ");
      j << "     ]}" << (f + 1 < results.size() ? "," : "") << "\n";
    }
    j << "  ]\n}\n";
  }
  if (!opt.csv.empty()) {
    std::ofstream c(opt.csv);
    if (!c) throw BadInput(opt.csv + ": cannot open for writing");
    c << "family,name,setting,ns_per_query,max_abs_error,rms_error,agreement,error_queries\n";
    for (const FamilyResult& fr : results) {
      for (const MethodResult& m : fr.all) {
        c << '"' << fr.family->name << "\"," << m.name << ",\"" << m.setting << "\","
          << m.ns_per_query << ',' << m.max_abs_error << ',' << m.rms_error << ',' << m.agreement
          << ',' << m.error_queries << '\n';
      }
    }
  }
  if (!opt.plot.empty()) WritePlot(head.all, opt.plot, head.family->name);
  for (const FamilyResult& fr : results) {
    std::printf("%s: %zu queries (%d in contact), tolerance %.3g m; SP default %.1f ns/query\n",
                fr.family->name.c_str(), fr.family->queries.size(), fr.contacts, fr.tol,
                fr.sp->ns_per_query);
    const auto setting = [](const std::string& v) { return v.empty() ? "none" : v.c_str(); };
    std::printf(
        "  ratios: mesh/sp %.4g (%s), sampling/sp %.4g (%s), sampling clipped/sp %.4g (%s), "
        "exact/sp %.4g\n",
        fr.ratios.mesh_over_sp, setting(fr.ratios.mesh_setting), fr.ratios.sampling_over_sp,
        setting(fr.ratios.sampling_setting), fr.ratios.sampling_clipped_over_sp,
        setting(fr.ratios.sampling_clipped_setting), fr.ratios.exact_over_sp);
    std::printf(
        "  with the deepest point within tolerance too (%d queries with a well-defined one): "
        "mesh/sp %.4g (%s), sampling/sp %.4g (%s), sampling clipped/sp %.4g (%s)\n",
        fr.isolated, fr.ratios.mesh_over_sp_point, setting(fr.ratios.mesh_point_setting),
        fr.ratios.sampling_over_sp_point, setting(fr.ratios.sampling_point_setting),
        fr.ratios.sampling_clipped_over_sp_point,
        setting(fr.ratios.sampling_clipped_point_setting));
    std::printf("  SP default settled by:");
    const double n = static_cast<double>(fr.family->queries.size());
    for (const geometry::SpDecision d : kDecisions) {
      const int count = fr.decisions[static_cast<int>(d)];
      if (count > 0) std::printf(" %s %.1f %%", geometry::ToString(d), 100 * count / n);
    }
    std::printf("; with a lifted pass %.1f %%, uniform starts %.1f %%\n",
                100 * fr.lifted_passes / n, 100 * fr.uniform_starts / n);
    for (const Goal& g : CheckGoals(fr)) {
      std::printf("  goal %-40s %10.4g  %s\n", g.what.c_str(), g.value, g.met ? "met" : "NOT met");
    }
  }
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
  app.add_flag("--quick", opt.quick, "reduced run (200 queries per family, coarse meshes only)");
  app.add_option("--queries", opt.queries, "number of random queries per family");
  app.add_option("--reps", opt.reps, "timing repetitions (median taken)");
  app.add_option("--seed", opt.seed, "random seed of the poses");
  app.add_option("--mesh-dir", opt.mesh_dir, "where the OBJ meshes are read / generated");
  app.add_option("--cases", cases, "evaluate the cases of this CSV (columns: README.md)");
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
