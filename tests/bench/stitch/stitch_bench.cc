// microdex-bench stitch: the knot-tying stitch moved by the tissue (station/stitch_tissue.h),
// error against run time (assets/scenes/README.md, "The stitch on the tissue").
//
//   microdex-bench stitch [--json FILE] [--quick] [--scene FILE] [--obj-dir DIR]
//                         [--jig-window FROM:TO:STEP [--window-relax S ...]]
//
// compliance: the patch's point compliance at the stitch's three rods (fem::CalcPointCompliance)
//   at tissue levels 5 … 8: its build time (median of 3), the largest relative error of the
//   off-diagonal entries against the rectangle's Green's function (the Navier point-load
//   series), of the diagonal against that function on the contact disc's rim, and the largest
//   asymmetry |C_ij − C_ji| / C_ij;
// in_plane: the patch's in-plane (plane-stress) compliance (fem::CalcInPlaneCompliance) at the
//   same levels, and level 9 in the full run: a rigid 1 mm disc in an annulus clamped at 8 mm,
//   at the patch's centre, against Muskhelishvili's closed form (its solve time and error), and
//   the stitch's 6 × 6 compliance (its build time, median of 3, and its largest difference from
//   the finest level's, relative to the largest entry);
// coupling: the scene's surgeon's knot (buttons 3, 2, the hands at rest) to the end of the hold,
//   with the rigid stitch (stitch_relax_s 0), the scene's, the same with the in-plane key
//   (knot_tying.stitch_in_plane) turned the other way, the in-plane stitch at the jig where the
//   normal-only stitch ties (the knot capsizes: the knot-topology scene's slip knot), and at other
//   relaxation times: the station step's median and p99 with their ratio to the rigid run's in
//   the same run, the bite's displacement at the end, how far the low-passed loads trail the
//   thread's (largest |load − force| over the largest |force|), the balance of the rods' loads
//   against the hands' pull along the normal, and the knot named;
// jig window (--jig-window FROM:TO:STEP): the six button pairs tied with the next throws' jig
//   (knot_tying.next_jig_x_m) over a range, with and without the in-plane key: the knot of each;
// cut-through: the same tie with the hands pulling the held ends 0 … 5 mm further out (in the
//   full run also with the in-plane key turned the other way)
//   (knot_tying.hold_pull_N_per_m sets the tension they then keep), with the scene's
//   bite_tear_N and without it: the hands' tension at the end, the bite's largest low-passed
//   load, how far the bite cut and whether it was pulled out, the rods' balance against the
//   hands' pull at the end, and the step median against the run without tearing.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "bench_util.h"
#include "common/fem/in_plane_compliance.h"
#include "common/fem/navier.h"
#include "common/fem/point_compliance.h"
#include "common/knot/obj.h"
#include "common/knot/stitch_knot.h"
#include "common/scene/scene.h"
#include "station/score.h"
#include "station/station_step.h"
#include "station/stitch_tissue.h"

namespace microdex::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::string Fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

struct ComplianceRow {
  int level = 0;
  double build_ms = 0;
  double off_diagonal_error = 0;
  double diagonal_error = 0;
  double asymmetry = 0;
};

ComplianceRow MeasureCompliance(const scene::SceneModel& scene,
                                const station::StitchOnTissue& stitch, int level) {
  fem::TissueDef def = scene.tissue->def;
  def.level = level;
  def.max_level = std::max(def.max_level, level);
  const fem::TissueModel model = fem::BuildTissueModel(def);
  const double radius_m = scene.tissue->contact_radius_m;
  std::vector<double> ms;
  fem::PointCompliance pc;
  for (int rep = 0; rep < 3; ++rep) {
    const auto t0 = Clock::now();
    pc = fem::CalcPointCompliance(model, stitch.p_S, radius_m, 4);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  fem::NavierDomain domain;
  domain.length_x_m = def.length_x_m;
  domain.length_y_m = def.length_y_m;
  domain.shear_modulus_Pa = def.shear_modulus_Pa;
  domain.thickness_m = def.thickness_m;
  ComplianceRow row;
  row.level = level;
  row.build_ms = Percentile(ms, 0.5);
  const auto& p = stitch.p_S;
  for (int i = 0; i < station::kStitchRods; ++i) {
    for (int j = 0; j < station::kStitchRods; ++j) {
      const double c = pc.c_m_per_N(i, j);
      if (i == j) {
        const double ref = fem::NavierPointLoadDisplacement_m_per_N(domain, p[j].x(), p[j].y(),
                                                                    p[j].x() + radius_m, p[j].y());
        row.diagonal_error = std::max(row.diagonal_error, std::abs(c / ref - 1));
      } else {
        const double ref = fem::NavierPointLoadDisplacement_m_per_N(domain, p[j].x(), p[j].y(),
                                                                    p[i].x(), p[i].y());
        row.off_diagonal_error = std::max(row.off_diagonal_error, std::abs(c / ref - 1));
        row.asymmetry = std::max(row.asymmetry, std::abs(c - pc.c_m_per_N(j, i)) / c);
      }
    }
  }
  return row;
}

struct InPlaneRow {
  int level = 0;
  double annulus_ms = 0;
  double annulus_error = 0;  // |C_fem / C_exact − 1|
  double stitch_ms = 0;
  double stitch_difference = 0;  // max |C − C_finest| / max |C_finest|
  Eigen::MatrixXd c_m_per_N;
};

InPlaneRow MeasureInPlane(const scene::SceneModel& scene, const station::StitchOnTissue& stitch,
                          int level) {
  const fem::TissueDef& def = scene.tissue->def;
  const double a_m = 1e-3, r_m = 8e-3, u_m = 1e-4;
  const Eigen::Vector2d centre(0.5 * def.length_x_m, 0.5 * def.length_y_m);
  InPlaneRow row;
  row.level = level;
  std::vector<double> annulus_ms, stitch_ms;
  for (int rep = 0; rep < 3; ++rep) {
    auto t0 = Clock::now();
    const fem::RigidDiscSolution disc = fem::SolveRigidDisc(def, level, centre, a_m, {u_m, 0}, r_m);
    annulus_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    const double exact = fem::RigidDiscInAnnulusCompliance_m_per_N(
        def.shear_modulus_Pa, def.poisson_ratio, def.thickness_m, a_m, r_m);
    row.annulus_error = std::abs(u_m / disc.reaction_N.x() / exact - 1);
    t0 = Clock::now();
    row.c_m_per_N =
        fem::CalcInPlaneCompliance(def, level, stitch.p_S, scene.tissue->contact_radius_m)
            .c_m_per_N;
    stitch_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  row.annulus_ms = Percentile(annulus_ms, 0.5);
  row.stitch_ms = Percentile(stitch_ms, 0.5);
  return row;
}

// One knot tied in the scene: the stitch's model (relaxation time, the in-plane key), where the
// next throws' jig sits, the buttons' throws, and the hands' extra pull and tear threshold.
struct CouplingCase {
  double relax_s = 0;
  bool in_plane = false;           // knot_tying.stitch_in_plane
  double next_jig_m = 0;           // knot_tying.next_jig_x_m
  double hold_pull_m = 0;          // the hands' extra pull in the hold
  double tear_N = 0;               // knot_tying.bite_tear_N
  unsigned first = 3, second = 2;  // the buttons: a double right throw, then a single left
};

struct CouplingRow {
  CouplingCase c;
  double hold_N = 0;  // the larger of the hands' pulls at the end
  double bite_load_max_N = 0;
  double cut_um = 0;
  bool pulled_out = false;
  std::vector<Eigen::Vector3d> polyline;  // the thread at the end, as the recogniser reads it
  double step_median_us = 0;
  double step_p99_us = 0;
  double median_ratio = 1;  // to the rigid run's
  double p99_ratio = 1;
  double bite_um = 0;
  double max_strain = 0;  // the thread's largest link strain, over the run
  double end_strain = 0;  // and at the end
  double trailing = 0;
  double balance = 0;
  std::string knot;
  std::string error;
};

CouplingRow MeasureCoupling(scene::SceneModel scene, const CouplingCase& c) {
  scene.knot_tying->stitch_relax_s = c.relax_s;
  scene.knot_tying->bite_tear_N = c.tear_N;
  scene.knot_tying->stitch_in_plane = c.in_plane;
  scene.knot_tying->next_jig_x_m = c.next_jig_m;
  CouplingRow row;
  row.c = c;
  try {
    station::Simulation sim(scene);
    state::StationState s = sim.MakeInitialState(1);
    const auto limit = static_cast<std::uint64_t>(scene.task.time_limit_s / sim.dt_s());
    std::vector<double> us;
    us.reserve(limit);
    while (s.step < limit && s.score.outcome == 0) {
      station::StationInput in;
      in.device.X_WT = scene.CalcIdealToolPose(0);
      in.second.X_WT = scene.CalcIdealSecondToolPose(0);
      in.second.gripper = 1;
      const std::uint64_t k = s.step;
      in.device.buttons = k >= 300 && k < 400 ? c.first : k >= 500 && k < 600 ? c.second : 0u;
      if (s.thread->tie.holding != 0) {
        in.device.X_WT.translation().x() += c.hold_pull_m;
        in.second.X_WT.translation().x() -= c.hold_pull_m;
      }
      const auto t0 = Clock::now();
      station::StepStation(sim, in, s);
      us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
      row.max_strain = std::max(row.max_strain, s.thread->thread.status.max_strain);
      row.bite_load_max_N =
          std::max(row.bite_load_max_N, s.thread->tie.stitch_load_N[station::kBiteRod]);
    }
    row.step_median_us = Percentile(us, 0.5);
    row.step_p99_us = Percentile(us, 0.99);
    const state::ThreadModuleState& t = *s.thread;
    row.hold_N = std::max(t.f_T_W.norm(), t.f_T2_W.norm());
    row.end_strain = t.thread.status.max_strain;
    row.cut_um = t.tie.bite_cut_m * 1e6;
    row.pulled_out = t.tie.bite_pulled_out != 0;
    const Eigen::Matrix3Xd& x = t.thread.x_W;
    std::vector<Eigen::Vector3d> nodes(static_cast<std::size_t>(x.cols()));
    for (Eigen::Index i = 0; i < x.cols(); ++i) nodes[static_cast<std::size_t>(i)] = x.col(i);
    row.knot = std::string(knot::StitchKnotName(station::RecogniseTiedKnot(scene, nodes)));
    row.polyline = station::CalcStitchKnotPolyline(scene, nodes);
    const std::optional<station::StitchOnTissue> stitch = station::MakeStitchOnTissue(scene, 4);
    if (stitch) {
      const state::KnotTieState& tie = t.tie;
      row.bite_um = stitch->Displacement_m(tie.stitch_load_N)[1] * 1e6;
      double largest = 0, sum = 0, trail = 0;
      for (int k = 0; k < station::kStitchRods; ++k) {
        const auto i = static_cast<std::size_t>(k);
        largest = std::max(largest, std::abs(tie.stitch_force_N[i]));
        trail = std::max(trail, std::abs(tie.stitch_load_N[i] - tie.stitch_force_N[i]));
        sum += tie.stitch_force_N[i];
      }
      const double hands = (t.f_T_W + t.f_T2_W).dot(stitch->n_W);
      row.trailing = largest > 0 ? trail / largest : 0;
      row.balance = largest > 0 ? std::abs(sum + hands) / largest : 0;
    }
  } catch (const std::exception& e) {
    row.error = e.what();
  }
  return row;
}

// Where each stitch model ties the surgeon's knot at the scene's relaxation time (0.5 s):
// the stitch that moves only along the patch's normal at 4.3 mm (the scene's jig; the knots
// scatter between 3.5 and 4.6 mm, --jig-window), the one that also moves in the patch's plane
// in a window from 3.5 to 4.0 mm in which all six button pairs tie their knots. With the
// in-plane key on, the surgeon's knot tied at 4.3 mm capsizes onto its last strand: the slip
// knot of the knot-topology scene (assets/knots/tied_slip.obj).
constexpr double kNormalOnlyJig_m = 4.3e-3;
constexpr double kInPlaneJig_m = 3.75e-3;

int Run(int argc, char** argv) {
  std::string json_path;
  bool quick = false;
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  std::string scene_path =
      std::string(root != nullptr ? root : ".") + "/assets/scenes/knot_tying.yaml";
  CLI::App app{"microdex-bench stitch: the knot-tying stitch on the tissue, error and cost"};
  app.add_option("--json", json_path, "write the report as JSON");
  app.add_flag("--quick", quick, "levels 5-6, the rigid stitch and the scene's relaxation time");
  app.add_option("--scene", scene_path, "the knot-tying scene");
  std::string obj_dir;
  app.add_option("--obj-dir", obj_dir,
                 "write each coupling and cut-through run's thread at the end as an OBJ polyline "
                 "in the tissue's frame (coupling_RELAXs[_in_plane]_jigJIGmm.obj, "
                 "cut_PULLmm_TEAR[_in_plane].obj), for microdex-bench knot and knots.tied");
  std::string window_spec;
  app.add_option("--jig-window", window_spec,
                 "FROM:TO:STEP in mm: also tie the six button pairs (3,2 4,1 1,2 2,1 1,1 2,2) with "
                 "knot_tying.next_jig_x_m over this range, with the scene's stitch and with the "
                 "in-plane key turned the other way, and name each knot (about a minute a jig)");
  std::vector<double> window_relax;
  app.add_option("--window-relax", window_relax,
                 "the relaxation times of the --jig-window runs (default: the scene's)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  scene::SceneModel scene;
  std::optional<station::StitchOnTissue> stitch;
  try {
    scene = scene::LoadScene(scene_path);
    stitch = station::MakeStitchOnTissue(scene, 4);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-bench stitch: %s\n", e.what());
    return 2;
  }
  if (!stitch) {
    std::fprintf(stderr,
                 "microdex-bench stitch: %s: expected a knot_tying scene with a tissue module and "
                 "knot_tying.stitch_relax_s > 0\n",
                 scene_path.c_str());
    return 2;
  }
  const std::vector<int> levels = quick ? std::vector<int>{5, 6} : std::vector<int>{5, 6, 7, 8};
  // Rigid first (the baseline), then the scene's relaxation time, then the others.
  const double scene_relax_s = scene.knot_tying->stitch_relax_s;
  std::vector<double> relax = {0.0, scene_relax_s};
  if (!quick) {
    for (const double r : {0.05, 0.1, 0.2, 0.3, 1.0}) {
      if (r != scene_relax_s) relax.push_back(r);
    }
  }
  // Cut-through: each pull without tearing (the baseline) and with the scene's threshold.
  const double scene_tear_N = scene.knot_tying->bite_tear_N;
  const std::vector<double> pulls_m =
      quick ? std::vector<double>{3e-3}
            : std::vector<double>{0.0, 1e-3, 2e-3, 3e-3, 4e-3, 4.5e-3, 5e-3};
  std::vector<int> in_plane_levels = levels;
  if (!quick) in_plane_levels.push_back(9);
  // The coupling runs: the rigid stitch (the cost's baseline), the scene's stitch, the same
  // relaxation with the in-plane key turned the other way (at that model's jig), the slip
  // knot's recipe (the in-plane stitch at the normal-only stitch's jig), then the other
  // relaxation times.
  const bool scene_in_plane = scene.knot_tying->stitch_in_plane;
  const double scene_jig_m = scene.knot_tying->next_jig_x_m;
  std::vector<CouplingCase> coupling_cases = {
      {.relax_s = 0, .in_plane = false, .next_jig_m = scene_jig_m},
      {.relax_s = scene_relax_s, .in_plane = scene_in_plane, .next_jig_m = scene_jig_m},
      {.relax_s = scene_relax_s,
       .in_plane = !scene_in_plane,
       .next_jig_m = scene_in_plane ? kNormalOnlyJig_m : kInPlaneJig_m},
      {.relax_s = scene_relax_s, .in_plane = true, .next_jig_m = kNormalOnlyJig_m}};
  for (std::size_t i = 2; i < relax.size(); ++i) {
    coupling_cases.push_back(
        {.relax_s = relax[i], .in_plane = scene_in_plane, .next_jig_m = scene_jig_m});
  }
  // The jig's window.
  std::vector<CouplingCase> window_cases;
  if (!window_spec.empty()) {
    double from = 0, to = 0, by = 0;
    if (std::sscanf(window_spec.c_str(), "%lf:%lf:%lf", &from, &to, &by) != 3 || !(by > 0) ||
        !(from > 0) || !(to >= from) || (to - from) / by > 100) {
      std::fprintf(stderr,
                   "microdex-bench stitch: --jig-window '%s': expected FROM:TO:STEP in mm, "
                   "0 < FROM <= TO, STEP > 0, at most 100 steps\n",
                   window_spec.c_str());
      return 2;
    }
    if (window_relax.empty()) window_relax.push_back(scene_relax_s);
    for (const double tau : window_relax) {
      for (const bool key : {scene_in_plane, !scene_in_plane}) {
        for (int i = 0; from + i * by <= to + 1e-9; ++i) {
          for (const auto& [a, b] : std::vector<std::pair<unsigned, unsigned>>{
                   {3, 2}, {4, 1}, {1, 2}, {2, 1}, {1, 1}, {2, 2}}) {
            window_cases.push_back({.relax_s = tau,
                                    .in_plane = key && tau > 0,
                                    .next_jig_m = (from + i * by) * 1e-3,
                                    .first = a,
                                    .second = b});
          }
        }
      }
    }
  }
  const int total = static_cast<int>(levels.size() + in_plane_levels.size() +
                                     coupling_cases.size() + window_cases.size() +
                                     (scene_tear_N > 0 ? (quick ? 2 : 4) * pulls_m.size() : 0));
  int done = 0;
  const auto start = Clock::now();
  std::vector<ComplianceRow> compliance;
  for (const int level : levels) {
    compliance.push_back(MeasureCompliance(scene, *stitch, level));
    Progress("compliance", ++done, total, start);
  }
  std::vector<InPlaneRow> in_plane;
  try {
    for (const int level : in_plane_levels) {
      in_plane.push_back(MeasureInPlane(scene, *stitch, level));
      Progress("in-plane", ++done, total, start);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-bench stitch: in-plane compliance: %s\n", e.what());
    return 2;
  }
  const Eigen::MatrixXd& finest = in_plane.back().c_m_per_N;
  for (InPlaneRow& r : in_plane) {
    r.stitch_difference =
        (r.c_m_per_N - finest).cwiseAbs().maxCoeff() / finest.cwiseAbs().maxCoeff();
  }
  std::vector<CouplingRow> coupling;
  for (const CouplingCase& c : coupling_cases) {
    coupling.push_back(MeasureCoupling(scene, c));
    Progress("coupling", ++done, total, start);
  }
  for (CouplingRow& c : coupling) {
    c.median_ratio = c.step_median_us / coupling[0].step_median_us;
    c.p99_ratio = c.step_p99_us / coupling[0].step_p99_us;
  }
  std::vector<CouplingRow> cut;
  // A pull without tearing (the baseline) and with the scene's threshold.
  const auto tie_both = [&](const CouplingCase& c) {
    const CouplingRow whole = MeasureCoupling(scene, c);
    Progress("cut-through", ++done, total, start);
    CouplingCase tearing = c;
    tearing.tear_N = scene_tear_N;
    CouplingRow torn = MeasureCoupling(scene, tearing);
    Progress("cut-through", ++done, total, start);
    torn.median_ratio = torn.step_median_us / whole.step_median_us;
    torn.p99_ratio = torn.step_p99_us / whole.step_p99_us;
    cut.push_back(whole);
    cut.push_back(torn);
  };
  for (const double pull_m : scene_tear_N > 0 ? pulls_m : std::vector<double>{}) {
    const CouplingCase c{.relax_s = scene_relax_s,
                         .in_plane = scene_in_plane,
                         .next_jig_m = scene_jig_m,
                         .hold_pull_m = pull_m};
    tie_both(c);
    if (quick) continue;
    // The same pulls with the in-plane key turned the other way, at that model's jig.
    CouplingCase other = c;
    other.in_plane = !scene_in_plane;
    other.next_jig_m = scene_in_plane ? kNormalOnlyJig_m : kInPlaneJig_m;
    tie_both(other);
  }
  std::vector<CouplingRow> window;
  for (const CouplingCase& c : window_cases) {
    window.push_back(MeasureCoupling(scene, c));
    window.back().polyline.clear();
    Progress("jig window", ++done, total, start);
  }
  if (!obj_dir.empty()) {
    const auto write = [&](const CouplingRow& r, const std::string& name, const std::string& what) {
      if (r.polyline.empty()) return true;
      try {
        knot::WriteObjPolyline(std::filesystem::path(obj_dir) / name, r.polyline,
                               {"microdex-bench stitch --obj-dir: " +
                                    std::filesystem::path(scene_path).filename().string() + ", " +
                                    what + ": " + r.knot,
                                "the tissue's frame: surface z = 0, z out of the tissue, metres"},
                               scene.thread->def.diameter_m);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "microdex-bench stitch: --obj-dir: %s\n", e.what());
        return false;
      }
      return true;
    };
    for (const CouplingRow& r : coupling) {
      const std::string tag = Fmt(r.c.relax_s) + "s" + (r.c.in_plane ? "_in_plane" : "") + "_jig" +
                              Fmt(r.c.next_jig_m * 1e3) + "mm";
      if (!write(r, "coupling_" + tag + ".obj",
                 "the surgeon's knot, the hands at rest, stitch_relax_s " + Fmt(r.c.relax_s) +
                     (r.c.in_plane ? ", stitch_in_plane" : "") + ", next_jig_x_m " +
                     Fmt(r.c.next_jig_m))) {
        return 2;
      }
    }
    for (const CouplingRow& r : cut) {
      const std::string name = "cut_" + Fmt(r.c.hold_pull_m * 1e3) + "mm_" +
                               (r.c.tear_N > 0 ? Fmt(r.c.tear_N * 1e3) + "mN" : "none") +
                               (r.c.in_plane ? "_in_plane" : "") + ".obj";
      if (!write(r, name,
                 "the surgeon's knot, the hands " + Fmt(r.c.hold_pull_m * 1e3) +
                     " mm further out in the hold, bite_tear_N " +
                     (r.c.tear_N > 0 ? Fmt(r.c.tear_N) : "0"))) {
        return 2;
      }
    }
  }
  std::printf("compliance at the rods (%s)\n", scene_path.c_str());
  std::printf("| level | build ms | off-diagonal error | diagonal error | asymmetry |\n");
  std::printf("|---|---|---|---|---|\n");
  for (const ComplianceRow& r : compliance) {
    std::printf("| %d | %.1f | %.2f %% | %.2f %% | %.2f %% |\n", r.level, r.build_ms,
                100 * r.off_diagonal_error, 100 * r.diagonal_error, 100 * r.asymmetry);
  }
  std::printf(
      "\nin-plane compliance (a 1 mm disc in an annulus clamped at 8 mm against Muskhelishvili; "
      "the stitch's 6 x 6 against level %d)\n",
      in_plane.back().level);
  std::printf("| level | annulus ms | annulus error | stitch ms | stitch difference |\n");
  std::printf("|---|---|---|---|---|\n");
  for (const InPlaneRow& r : in_plane) {
    std::printf("| %d | %.1f | %.2f %% | %.1f | %.2f %% |\n", r.level, r.annulus_ms,
                100 * r.annulus_error, r.stitch_ms, 100 * r.stitch_difference);
  }
  std::printf("\ncoupling (surgeon's knot, hands at rest; step: the whole station step)\n");
  std::printf(
      "| stitch_relax_s | in-plane | next jig mm | step median us | p99 us | median / rigid | "
      "p99 / rigid | bite um | trailing | balance | strain max / end | knot |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const CouplingRow& r : coupling) {
    if (!r.error.empty()) {
      std::printf("| %.3g | %s | %.3g | refused: %s |\n", r.c.relax_s, r.c.in_plane ? "yes" : "no",
                  r.c.next_jig_m * 1e3, r.error.c_str());
      continue;
    }
    std::printf(
        "| %.3g | %s | %.3g | %.1f | %.1f | %.3f | %.3f | %+.1f | %.3f | %.3f | %.3f / %.3f | %s "
        "|\n",
        r.c.relax_s, r.c.in_plane ? "yes" : "no", r.c.next_jig_m * 1e3, r.step_median_us,
        r.step_p99_us, r.median_ratio, r.p99_ratio, r.bite_um, r.trailing, r.balance, r.max_strain,
        r.end_strain, r.knot.c_str());
  }
  if (!cut.empty()) {
    std::printf(
        "\ncut-through (the hands pulling the held ends further out; median / untorn: the run "
        "without tearing at the same pull)\n");
    std::printf(
        "| in-plane | hold pull mm | bite_tear_N mN | hands mN | bite load max mN | cut um | "
        "pulled out | balance | strain max / end | step median us | median / untorn | knot |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const CouplingRow& r : cut) {
      std::printf(
          "| %s | %.1f | %s | %.1f | %.2f | %.1f | %s | %.3f | %.3f / %.3f | %.1f | %s | %s |\n",
          r.c.in_plane ? "yes" : "no", r.c.hold_pull_m * 1e3,
          r.c.tear_N > 0 ? Fmt(r.c.tear_N * 1e3).c_str() : "none", r.hold_N * 1e3,
          r.bite_load_max_N * 1e3, r.cut_um, r.pulled_out ? "yes" : "no", r.balance, r.max_strain,
          r.end_strain, r.step_median_us, r.c.tear_N > 0 ? Fmt(r.median_ratio).c_str() : "1",
          r.knot.c_str());
    }
  }
  if (!window.empty()) {
    // One line per stitch model and jig: the knot of each button pair (the right ones: 3,2 and
    // 4,1 surgeon's, 1,2 and 2,1 square, 1,1 and 2,2 granny).
    std::printf(
        "\njig window (the knot of each button pair by next_jig_x_m; * where it is not the "
        "pair's: 3,2 and 4,1 a surgeon's knot, 1,2 and 2,1 square, 1,1 and 2,2 granny)\n");
    std::printf(
        "| stitch_relax_s | in-plane | next jig mm | 3,2 | 4,1 | 1,2 | 2,1 | 1,1 | 2,2 |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (std::size_t i = 0; i + 6 <= window.size(); i += 6) {
      const CouplingCase& c = window[i].c;
      std::printf("| %.3g | %s | %.3g |", c.relax_s, c.in_plane ? "yes" : "no", c.next_jig_m * 1e3);
      for (std::size_t j = i; j < i + 6; ++j) {
        const CouplingRow& r = window[j];
        const char* want = r.c.first >= 3            ? "surgeons"
                           : r.c.first == r.c.second ? "granny"
                                                     : "square";
        std::printf(" %s%s |", r.error.empty() ? r.knot.c_str() : "refused",
                    r.knot == want ? "" : "*");
      }
      std::printf("\n");
    }
  }
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    if (!out) {
      std::fprintf(stderr, "microdex-bench stitch: %s: cannot write\n", json_path.c_str());
      return 2;
    }
    out << "{\"scene\": \"" << scene_path << "\", \"compliance\": [";
    for (std::size_t i = 0; i < compliance.size(); ++i) {
      const ComplianceRow& r = compliance[i];
      out << (i ? ", " : "") << "{\"level\": " << r.level << ", \"build_ms\": " << r.build_ms
          << ", \"off_diagonal_error\": " << r.off_diagonal_error
          << ", \"diagonal_error\": " << r.diagonal_error << ", \"asymmetry\": " << r.asymmetry
          << "}";
    }
    out << "], \"in_plane\": [";
    for (std::size_t i = 0; i < in_plane.size(); ++i) {
      const InPlaneRow& r = in_plane[i];
      out << (i ? ", " : "") << "{\"level\": " << r.level << ", \"annulus_ms\": " << r.annulus_ms
          << ", \"annulus_error\": " << r.annulus_error << ", \"stitch_ms\": " << r.stitch_ms
          << ", \"stitch_difference\": " << r.stitch_difference << "}";
    }
    out << "], \"coupling\": [";
    for (std::size_t i = 0; i < coupling.size(); ++i) {
      const CouplingRow& r = coupling[i];
      out << (i ? ", " : "") << "{\"stitch_relax_s\": " << r.c.relax_s
          << ", \"in_plane\": " << (r.c.in_plane ? "true" : "false")
          << ", \"next_jig_x_m\": " << r.c.next_jig_m
          << ", \"step_median_us\": " << r.step_median_us << ", \"step_p99_us\": " << r.step_p99_us
          << ", \"median_ratio\": " << r.median_ratio << ", \"p99_ratio\": " << r.p99_ratio
          << ", \"bite_um\": " << r.bite_um << ", \"trailing\": " << r.trailing
          << ", \"balance\": " << r.balance << ", \"max_strain\": " << r.max_strain
          << ", \"end_strain\": " << r.end_strain << ", \"knot\": \"" << r.knot << "\""
          << ", \"refused\": " << (r.error.empty() ? "false" : "true") << "}";
    }
    out << "], \"cut_through\": [";
    for (std::size_t i = 0; i < cut.size(); ++i) {
      const CouplingRow& r = cut[i];
      out << (i ? ", " : "") << "{\"in_plane\": " << (r.c.in_plane ? "true" : "false")
          << ", \"hold_pull_m\": " << r.c.hold_pull_m << ", \"bite_tear_N\": " << r.c.tear_N
          << ", \"hands_N\": " << r.hold_N << ", \"bite_load_max_N\": " << r.bite_load_max_N
          << ", \"cut_m\": " << r.cut_um * 1e-6
          << ", \"pulled_out\": " << (r.pulled_out ? "true" : "false")
          << ", \"balance\": " << r.balance << ", \"max_strain\": " << r.max_strain
          << ", \"end_strain\": " << r.end_strain << ", \"step_median_us\": " << r.step_median_us
          << ", \"median_ratio\": " << r.median_ratio << ", \"knot\": \"" << r.knot << "\"}";
    }
    out << "], \"jig_window\": [";
    for (std::size_t i = 0; i < window.size(); ++i) {
      const CouplingRow& r = window[i];
      out << (i ? ", " : "") << "{\"stitch_relax_s\": " << r.c.relax_s
          << ", \"in_plane\": " << (r.c.in_plane ? "true" : "false")
          << ", \"next_jig_x_m\": " << r.c.next_jig_m << ", \"buttons\": [" << r.c.first << ", "
          << r.c.second << "], \"knot\": \"" << r.knot << "\""
          << ", \"refused\": " << (r.error.empty() ? "false" : "true") << "}";
    }
    out << "]}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(
    stitch, "stitch", "the knot-tying stitch moved by the tissue: compliance error, coupling cost",
    Run);

}  // namespace microdex::bench
