// microdex-bench thread: stability region, error against run time, and speed of the suture
// thread (thesis chapter 5), for each integrator.
//
//   microdex-bench thread [--json FILE]                  speed during knot tying (default)
//   microdex-bench thread --stability --json FILE [--plot FILE.png]
//   microdex-bench thread --accuracy --json FILE
//   microdex-bench thread --adversarial [--steps 1000000] [--json FILE]
//   microdex-bench thread --tie 2 | 1r,1l | 2r,1l [--nodes N] [--stitch] [--obj FILE] [--json FILE]
//                         tie the throws, pull each to 15 mN (--pull-tension N, newtons),
//                         hold 20 mN for 2 s; report per phase;
//                         --stitch: around a stitch (an 18 mm thread through three rods);
//                         --stitch-geometry X,DEPTH,OFFSET,ROD_R,GUIDE_R,START,LENGTH (mm)
//                         --force-limited-pull: each hand limits its pull to the pull tension;
//                         --next-throw-offset MM: the next throw's jig this far beyond the
//                         knot (default 3 mm);
//                         --obj with --stitch: in the tissue's frame (the knot quiz's shapes)
//   microdex-bench thread --tie-matrix [--json FILE] [--markdown FILE]
//                         five knots x 129..513 nodes x mu 0.1..0.3 (README table), the same
//                         pull tension for every case
//   --friction MU --object-friction MU --exact-pairs N --friction-contacts N
//                                                        contact model (tie and speed)
//   --quick                                              reduced sizes (CTest)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "common/base/json_text.h"
#include "common/knot/obj.h"
#include "common/thread/grasp.h"
#include "common/thread/sphere_bvh.h"
#include "common/thread/thread_contacts.h"
#include "common/thread/thread_forces.h"
#include "common/thread/thread_step.h"
#include "tests/support/thread_scenarios.h"

namespace microdex::thread {
namespace {

using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::string Num(double v) { return JsonNumber(v, 6); }

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("--json/--plot: cannot write '" + path + "'");
  out << text;
}

constexpr Integrator kIntegrators[] = {Integrator::kSemiImplicitEuler,
                                       Integrator::kLinearlyImplicitEuler};

// ---- stability -----------------------------------------------------------------------------
int RunStability(bool quick, const std::string& json, const std::string& plot) {
  std::vector<double> ks, kb, mass, dts;
  if (quick) {
    ks = {1e2, 1e6};
    kb = {1e-7};
    mass = {1e-5};
    dts = {1e-4, 1e-3};
  } else {
    // The ranges, sampled every two decades (stretch), three (bending) and at the
    // ends and middle (mass), so the sweep runs in a few minutes on one core.
    ks = {1e0, 1e2, 1e4, 1e6, 1e8};
    kb = {1e-9, 1e-6, 1e-3};
    mass = {1e-7, 1e-5, 1e-3, 1e-2};
    dts = {1e-4, 2.5e-4, 1e-3, 4e-3};
  }
  std::ostringstream runs;
  // Largest stable dt per (integrator, k_s, mass), minimised over k_b: the PNG map.
  struct Cell {
    int integrator;
    double ks, mass, best_dt;
  };
  std::vector<Cell> cells;
  int stable_count[2] = {0, 0};
  int total = 0;
  bool first = true;
  for (int ii = 0; ii < 2; ++ii) {
    for (double k : ks) {
      for (double m : mass) {
        double best_dt = 0.0;  // largest dt stable for every k_b
        for (double dt : dts) {
          bool all = true;
          for (double b : kb) {
            SwingPullOptions opt;
            opt.integrator = kIntegrators[ii];
            opt.time_step_s = dt;
            const SwingPullReport r = RunSwingPull(SwingPullDef(k, b, m), opt);
            all = all && r.stable();
            stable_count[ii] += r.stable() ? 1 : 0;
            ++total;
            runs << (first ? "" : ",\n") << "    {\"integrator\": \""
                 << IntegratorName(kIntegrators[ii]) << "\", \"stretch_N_per_m\": " << Num(k)
                 << ", \"bend_N_m\": " << Num(b) << ", \"node_mass_kg\": " << Num(m)
                 << ", \"dt_s\": " << Num(dt) << ", \"stable\": " << (r.stable() ? "true" : "false")
                 << ", \"finite\": " << (r.finite ? "true" : "false")
                 << ", \"energy_bounded\": " << (r.energy_bounded ? "true" : "false")
                 << ", \"strain_ok\": " << (r.strain_ok ? "true" : "false")
                 << ", \"no_tunnelling\": " << (r.no_tunnelling ? "true" : "false")
                 << ", \"max_strain\": " << Num(r.max_strain) << "}";
            first = false;
          }
          if (all) best_dt = std::max(best_dt, dt);
        }
        cells.push_back({ii, k, m, best_dt});
      }
    }
  }
  // Table: largest dt stable for all k_b, rows k_s, columns mass, one block per integrator.
  for (int ii = 0; ii < 2; ++ii) {
    std::printf("\n%s: largest stable dt [ms] over all bending stiffnesses (- : none)\n",
                IntegratorName(kIntegrators[ii]));
    std::printf("%12s", "k_s\\m [kg]");
    for (double m : mass) std::printf(" %8.0e", m);
    std::printf("\n");
    for (double k : ks) {
      std::printf("%12.0e", k);
      for (double m : mass) {
        for (const Cell& c : cells) {
          if (c.integrator == ii && c.ks == k && c.mass == m) {
            if (c.best_dt > 0) {
              std::printf(" %8.2f", c.best_dt * 1e3);
            } else {
              std::printf(" %8s", "-");
            }
          }
        }
      }
      std::printf("\n");
    }
  }
  std::printf("\nstable runs: %s %d, %s %d, of %d each\n", IntegratorName(kIntegrators[0]),
              stable_count[0], IntegratorName(kIntegrators[1]), stable_count[1], total / 2);
  if (!json.empty()) {
    std::ostringstream out;
    out << "{\n  \"study\": \"stability\",\n  \"criteria\": \"finite, energy <= 100x reference, "
           "max link strain < 0.1, no link through the rod or non-adjacent links < 0.5 d\",\n"
        << "  \"summary\": [{\"integrator\": \"" << IntegratorName(kIntegrators[0])
        << "\", \"stable_runs\": " << stable_count[0] << ", \"runs\": " << total / 2
        << "}, {\"integrator\": \"" << IntegratorName(kIntegrators[1])
        << "\", \"stable_runs\": " << stable_count[1] << ", \"runs\": " << total / 2 << "}],\n"
        << "  \"runs\": [\n"
        << runs.str() << "\n  ]\n}\n";
    WriteFile(json, out.str());
  }
  if (!plot.empty()) {
    const std::string dat = plot + ".dat";
    std::ostringstream d;
    for (int ii = 0; ii < 2; ++ii) {
      for (double k : ks) {
        for (const Cell& c : cells) {
          if (c.integrator == ii && c.ks == k) {
            d << std::log10(c.ks) << " " << std::log10(c.mass) << " "
              << (c.best_dt > 0 ? c.best_dt * 1e3 : 0.0) << "\n";
          }
        }
        d << "\n";
      }
      d << "\n\n";
    }
    WriteFile(dat, d.str());
    std::ostringstream gp;
    gp << "set terminal pngcairo size 1200,500\nset output '" << plot << "'\n"
       << "set multiplot layout 1,2 title 'Largest stable dt [ms] (all bending stiffnesses)'\n"
       << "set xlabel 'log10 stretch stiffness [N/m]'\nset ylabel 'log10 node mass [kg]'\n"
       << "set cbrange [0:4]\nset view map\n";
    for (int ii = 0; ii < 2; ++ii) {
      gp << "set title '" << IntegratorName(kIntegrators[ii]) << "'\n"
         << "plot '" << dat << "' index " << ii << " using 1:2:3 with points pt 5 ps 3 "
         << "palette notitle\n";
    }
    gp << "unset multiplot\n";
    const std::string script = plot + ".gp";
    WriteFile(script, gp.str());
    const std::string cmd = "gnuplot '" + script + "'";
    if (std::system(cmd.c_str()) != 0) {
      std::fprintf(stderr, "gnuplot failed; data in %s\n", dat.c_str());
    }
  }
  return 0;
}

// ---- accuracy ------------------------------------------------------------------------------
double SampleError(const std::vector<Eigen::Matrix3Xd>& a, const std::vector<Eigen::Matrix3Xd>& b,
                   size_t max_samples = std::numeric_limits<size_t>::max()) {
  double worst = 0.0;
  const size_t n = std::min({a.size(), b.size(), max_samples});
  if (max_samples < std::min(a.size(), b.size())) {
    for (size_t k = 0; k < n; ++k) {
      worst = std::max(worst, std::sqrt((a[k] - b[k]).colwise().squaredNorm().mean()));
    }
    return worst;
  }
  for (size_t k = 0; k < n; ++k) {
    const double rms = std::sqrt((a[k] - b[k]).colwise().squaredNorm().mean());
    worst = std::max(worst, rms);
  }
  return n == a.size() && n == b.size() ? worst : std::numeric_limits<double>::infinity();
}

int RunAccuracy(bool quick, const std::string& json) {
  constexpr size_t kSmoothSamples = 31;  // 0 .. 0.6 s at 20 ms
  // A soft model on which the baseline is stable at small steps (k_s = 300 N/m, node mass
  // 1e-5 kg: explicit limit 2 / sqrt(4 k / m) = 0.18 ms), swung without the rod so that the
  // trajectory has no contact events and errors can converge.
  ThreadDef def = SwingPullDef(3e2, 1e-7, 1e-5);
  // A viscous surrounding (relaxation time m / c ~ 0.1 s): without it the whipping thread is
  // chaotic and any two step sizes drift apart by millimetres whatever their accuracy.
  def.drag_N_s_per_m2 = 0.05;
  const double ref_dt = quick ? 1e-5 : 2.5e-6;
  const std::vector<double> dts =
      quick ? std::vector<double>{5e-5, 1e-4}
            : std::vector<double>{2.5e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 4e-3};
  SwingPullOptions ref_opt;
  // The reference is the symplectic baseline at a step far below its stability limit: implicit
  // Euler, even at 2.5 us, damps the stretch vibrations numerically (rate omega^2 h / 2 ~
  // 150 / s against the drag's 8 / s) and is itself 0.6 mm away from the converged motion.
  ref_opt.integrator = Integrator::kSemiImplicitEuler;
  ref_opt.time_step_s = ref_dt;
  ref_opt.stop_when_unstable = false;
  ref_opt.rod = false;
  const SwingPullReport ref = RunSwingPull(def, ref_opt);
  std::printf("reference: %s dt = %g s, stable = %d, self contacts <= %d\n",
              IntegratorName(ref_opt.integrator), ref_dt, ref.stable(), ref.max_self_contacts);
  std::printf("%-24s %8s %14s %7s %14s %14s %7s\n", "integrator", "dt[ms]", "error[m]", "order",
              "error_all[m]", "ns/step", "stable");
  std::ostringstream runs;
  bool first = true;
  for (Integrator integ : kIntegrators) {
    double prev_err = 0.0, prev_dt = 0.0;
    for (double dt : dts) {
      SwingPullOptions opt = ref_opt;
      opt.integrator = integ;
      opt.time_step_s = dt;
      std::vector<double> per_step;
      SwingPullReport r;
      for (int rep = 0; rep < (quick ? 1 : 3); ++rep) {
        const auto t0 = Clock::now();
        r = RunSwingPull(def, opt);
        per_step.push_back(Seconds(t0, Clock::now()) / std::max(1, r.steps));
      }
      // The smooth window: the first 0.6 s (drop and swing). At ~0.65 s the thread is flung
      // over the top, an event so sensitive that every step size lands 0.1-0.6 mm apart
      // afterwards; the whole trajectory's error is reported beside it.
      const double err = r.stable() ? SampleError(r.samples, ref.samples, kSmoothSamples)
                                    : std::numeric_limits<double>::infinity();
      const double err_all = r.stable() ? SampleError(r.samples, ref.samples)
                                        : std::numeric_limits<double>::infinity();
      // Observed order against the previous (smaller) step.
      const double order = prev_err > 0.0 && std::isfinite(err) && std::isfinite(prev_err)
                               ? std::log(err / prev_err) / std::log(dt / prev_dt)
                               : std::numeric_limits<double>::quiet_NaN();
      prev_err = err;
      prev_dt = dt;
      const double ns = Median(per_step) * 1e9;
      std::printf("%-24s %8.3f %14.4e %7.2f %14.4e %14.0f %7d\n", IntegratorName(integ), dt * 1e3,
                  err, order, err_all, ns, r.stable());
      runs << (first ? "" : ",\n") << "    {\"integrator\": \"" << IntegratorName(integ)
           << "\", \"dt_s\": " << Num(dt) << ", \"position_error_m\": " << Num(err)
           << ", \"observed_order\": " << Num(order)
           << ", \"position_error_whole_m\": " << Num(err_all) << ", \"ns_per_step\": " << Num(ns)
           << ", \"stable\": " << (r.stable() ? "true" : "false") << "}";
      first = false;
    }
  }
  std::printf("(the cost per step includes the study's O(n^2) tunnelling check)\n");
  if (!json.empty()) {
    std::ostringstream out;
    out << "{\n  \"study\": \"accuracy\",\n  \"model\": {\"stretch_N_per_m\": 300, "
           "\"bend_N_m\": 1e-7, \"node_mass_kg\": 1e-5, \"drag_N_s_per_m2\": 0.05, "
           "\"nodes\": 33, \"rod\": false},\n"
        << "  \"reference\": {\"integrator\": \"" << IntegratorName(ref_opt.integrator)
        << "\", \"dt_s\": " << Num(ref_dt)
        << "},\n  \"error\": \"max over the 20 ms samples of 0..0.6 s of the RMS node position "
           "difference (whole 2 s: position_error_whole_m); null when unstable\",\n"
        << "  \"runs\": [\n"
        << runs.str() << "\n  ]\n}\n";
    WriteFile(json, out.str());
  }
  return 0;
}

// Contact model options of the command line (--friction MU, --object-friction MU,
// --exact-pairs N, --friction-contacts N), applied on top of a thread's defaults; negative: keep
// the default.
struct ContactOverrides {
  double friction = -1.0;
  double object_friction = -1.0;
  int exact_pairs = -1;
  int friction_contacts = -1;
  int friction_self_contacts = -1;
  double contact_force = -1.0;
  ThreadDef Apply(ThreadDef def) const {
    if (contact_force >= 0.0) def.contact_force_N = contact_force;
    if (friction >= 0.0) def.friction_coefficient = friction;
    if (object_friction >= 0.0) def.object_friction_coefficient = object_friction;
    if (exact_pairs >= 0) def.exact_contact_pairs = exact_pairs;
    if (friction_contacts >= 0) def.friction_contacts = friction_contacts;
    if (friction_self_contacts >= 0) def.friction_self_contacts = friction_self_contacts;
    return def;
  }
};

// ---- speed ---------------------------------------------------------------------------------
int RunSpeed(bool quick, const std::string& json, const ContactOverrides& contact) {
  const std::vector<int> nodes =
      quick ? std::vector<int>{65, 129} : std::vector<int>{65, 129, 257, 513, 1025};
  const int max_steps = quick ? 300 : 3000;
  std::ostringstream runs;
  bool first = true;
  std::printf("%-24s %6s %12s %14s %14s %7s %8s\n", "integrator", "nodes", "steps/s",
              "collision_ns", "all_pairs_ns", "ratio", "resets");
  std::vector<LinkPair> bvh_pairs, all_pairs;
  // The two queries must find the same set (checked outside the timed sections).
  auto same_set = [](std::vector<LinkPair>& a, int na, std::vector<LinkPair>& b, int nb) {
    auto less = [](const LinkPair& u, const LinkPair& v) {
      return u.a != v.a ? u.a < v.a : u.b < v.b;
    };
    if (na != nb || na > static_cast<int>(a.size())) return false;
    std::sort(a.begin(), a.begin() + na, less);
    std::sort(b.begin(), b.begin() + nb, less);
    return std::equal(
        a.begin(), a.begin() + na, b.begin(),
        [](const LinkPair& u, const LinkPair& v) { return u.a == v.a && u.b == v.b; });
  };
  for (Integrator integ : kIntegrators) {
    for (int n : nodes) {
      ThreadDef def = contact.Apply(KnotTyingDef(n));
      def.integrator = integ;
      const ThreadModel model = MakeThreadModel(def);
      ThreadState state =
          MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
      ThreadWorkspace ws = MakeThreadWorkspace(model);
      const KnotTyingHands hands = SetUpKnotTying(model, state);
      KnotThrowOptions tie;
      tie.passes = 2;
      tie.speed_m_per_s = 0.01;  // a faster hand, to reach the knot within the timed steps
      KnotThrowScript script(model, state, hands, tie);
      ThreadWorkspace script_ws = MakeThreadWorkspace(model);
      SphereBvhSpheres spheres = MakeSphereBvhSpheres(model.bvh);
      bvh_pairs.assign(4 * model.contact_capacity, LinkPair{});
      all_pairs.assign(4 * model.contact_capacity, LinkPair{});
      const int cap = static_cast<int>(bvh_pairs.size());
      std::vector<double> step_s, bvh_s, all_s;
      for (int k = 0; k < max_steps && !script.done(); ++k) {
        const auto t0 = Clock::now();
        script.Step(model, script_ws, state);
        step_s.push_back(Seconds(t0, Clock::now()));
        if (k % 10 == 0) {
          // The self-collision query on this frame: the hierarchy (refit + FindCollision)
          // against every pair of leaf spheres (leaf refit + all pairs), same frame, same run.
          int found_bvh = 0, found_all = 0;
          auto c0 = Clock::now();
          RefitSphereBvh(model.bvh, state.x_W, model.bvh_inflate_m, spheres);
          found_bvh = FindSelfCollisions(model.bvh, spheres, bvh_pairs.data(), cap);
          bvh_s.push_back(Seconds(c0, Clock::now()));
          c0 = Clock::now();
          RefitSphereBvhLeaves(model.bvh, state.x_W, model.bvh_inflate_m, spheres);
          found_all = FindSelfCollisionsAllPairs(model.bvh, spheres, all_pairs.data(), cap);
          all_s.push_back(Seconds(c0, Clock::now()));
          if (!same_set(bvh_pairs, found_bvh, all_pairs, found_all)) {
            std::fprintf(stderr, "BVH found %d pairs, all pairs %d: not the same set\n", found_bvh,
                         found_all);
            return 1;
          }
        }
      }
      const double sps = 1.0 / Median(step_s);
      const double cns = Median(bvh_s) * 1e9;
      const double ans = Median(all_s) * 1e9;
      const long long resets = state.status.nonfinite_resets + state.status.factorization_failures;
      std::printf("%-24s %6d %12.0f %14.0f %14.0f %7.1f %8lld\n", IntegratorName(integ), n, sps,
                  cns, ans, ans / cns, resets);
      runs << (first ? "" : ",\n") << "    {\"integrator\": \"" << IntegratorName(integ)
           << "\", \"nodes\": " << n << ", \"steps_per_s\": " << Num(sps)
           << ", \"collision_ns\": " << Num(cns) << ", \"collision_all_pairs_ns\": " << Num(ans)
           << ", \"collision_ratio\": " << Num(ans / cns) << ", \"steps\": " << step_s.size()
           << ", \"rolled_back_steps\": " << resets << "}";
      first = false;
    }
  }
  // BVH against all pairs at 257 nodes, on a thread coiled into a tight helix (many close
  // pairs, the knot's worst case).
  const int n = 257;
  const ThreadModel model = MakeThreadModel(KnotTyingDef(n));
  Eigen::Matrix3Xd x(3, n);
  const double pitch = 4.0 * model.def.diameter_m;
  const double radius = 0.6e-3;
  const double dphi = model.rest_length_m[0] / radius;
  for (int i = 0; i < n; ++i) {
    x.col(i) = Eigen::Vector3d(radius * std::cos(i * dphi), radius * std::sin(i * dphi),
                               pitch * i * dphi / (2.0 * M_PI));
  }
  SphereBvhSpheres spheres = MakeSphereBvhSpheres(model.bvh);
  bvh_pairs.assign(model.contact_capacity * 4, LinkPair{});
  all_pairs.assign(model.contact_capacity * 4, LinkPair{});
  const int cap = static_cast<int>(bvh_pairs.size());
  const int reps = quick ? 50 : 2000;
  std::vector<double> bvh_s, all_s;
  int bvh_count = 0, all_count = 0;
  for (int r = 0; r < reps; ++r) {
    auto t0 = Clock::now();
    RefitSphereBvh(model.bvh, x, model.bvh_inflate_m, spheres);
    bvh_count = FindSelfCollisions(model.bvh, spheres, bvh_pairs.data(), cap);
    bvh_s.push_back(Seconds(t0, Clock::now()));
    t0 = Clock::now();
    RefitSphereBvhLeaves(model.bvh, x, model.bvh_inflate_m, spheres);
    all_count = FindSelfCollisionsAllPairs(model.bvh, spheres, all_pairs.data(), cap);
    all_s.push_back(Seconds(t0, Clock::now()));
  }
  if (!same_set(bvh_pairs, bvh_count, all_pairs, all_count)) {
    std::fprintf(stderr, "helix: BVH found %d pairs, all pairs %d: not the same set\n", bvh_count,
                 all_count);
    return 1;
  }
  const double bvh_ns = Median(bvh_s) * 1e9;
  const double all_ns = Median(all_s) * 1e9;
  std::printf(
      "\nself-collision query at %d nodes: BVH %.0f ns, all pairs %.0f ns, ratio %.1f "
      "(%d / %d pairs)\n",
      n, bvh_ns, all_ns, all_ns / bvh_ns, bvh_count, all_count);
  if (!json.empty()) {
    std::ostringstream out;
    out << "{\n  \"study\": \"speed\",\n  \"trajectory\": \"knot tying (double overhand jig)\",\n"
        << "  \"runs\": [\n"
        << runs.str() << "\n  ],\n"
        << "  \"bvh_vs_all_pairs\": {\"nodes\": " << n << ", \"bvh_ns\": " << Num(bvh_ns)
        << ", \"all_pairs_ns\": " << Num(all_ns) << ", \"ratio\": " << Num(all_ns / bvh_ns)
        << ", \"pairs\": " << bvh_count << ", \"all_pairs_pairs\": " << all_count << "}\n}\n";
    WriteFile(json, out.str());
  }
  return 0;
}

// ---- tie -----------------------------------------------------------------------------------
std::string PhaseJson(const TiePhaseReport& r) {
  std::ostringstream o;
  o << "{\"throw\": " << r.throw_index << ", \"phase\": \"" << r.phase << "\", \"knot\": \""
    << r.knot << "\", \"steps\": " << r.steps
    << ", \"min_distance_over_d\": " << Num(r.min_distance_over_d)
    << ", \"steps_per_s\": " << Num(r.steps_per_s) << ", \"tick_p99_us\": " << Num(r.tick_p99_us)
    << ", \"max_self_contacts\": " << r.max_self_contacts
    << ", \"f_standing_max_N\": " << Num(r.f_standing_max_N)
    << ", \"f_driver_max_N\": " << Num(r.f_driver_max_N)
    << ", \"max_projection_sweeps\": " << r.max_projection_sweeps
    << ", \"pair_tests_per_step\": " << Num(r.pair_tests_per_step)
    << ", \"projection_parts_per_step\": " << Num(r.projection_parts_per_step)
    << ", \"projection_sweeps_per_step\": " << Num(r.projection_sweeps_per_step)
    << ", \"max_projection_residual_over_d\": " << Num(r.max_projection_residual_over_d) << "}";
  return o.str();
}

std::string TieJson(const std::string& spec, int nodes, double mu, const TieReport& r) {
  std::ostringstream o;
  o << "{\"throws\": \"" << spec << "\", \"nodes\": " << nodes << ", \"friction\": " << Num(mu)
    << ", \"knot\": \"" << r.knot << "\", \"knot_after_pull\": \"" << r.knot_after_pull
    << "\", \"min_distance_over_d\": " << Num(r.min_distance_over_d)
    << ", \"held\": " << (r.held ? "true" : "false")
    << ", \"hold_shift_m\": " << Num(r.hold_shift_m)
    << ", \"pulled_tight\": " << (r.pulled_tight ? "true" : "false")
    << ", \"steps_per_s\": " << Num(r.steps_per_s) << ", \"tick_p99_us\": " << Num(r.tick_p99_us)
    << ", \"rollbacks\": " << r.rollbacks << ", \"max_strain\": " << Num(r.max_strain)
    << ", \"max_strain_hold\": " << Num(r.max_strain_hold) << ",\n   \"phases\": [";
  for (size_t k = 0; k < r.phases.size(); ++k) {
    o << (k ? ",\n     " : "\n     ") << PhaseJson(r.phases[k]);
  }
  o << "]}";
  return o.str();
}

void PrintPhase(const TiePhaseReport& r) {
  std::printf(
      "  %s %-5s %5d steps: knot %-16s min dist %.3f d, %6.0f steps/s (median), tick p99 %5.0f "
      "us, self contacts max %3d, f max %.3g / %.3g N, projection sweeps max %d residual %.3f d, "
      "%.0f pair tests/step, %.2f parts and %.1f sweeps/step\n",
      r.throw_index > 0 ? ("throw " + std::to_string(r.throw_index)).c_str() : "       ",
      r.phase.c_str(), r.steps, r.knot.c_str(), r.min_distance_over_d, r.steps_per_s, r.tick_p99_us,
      r.max_self_contacts, r.f_standing_max_N, r.f_driver_max_N, r.max_projection_sweeps,
      r.max_projection_residual_over_d, r.pair_tests_per_step, r.projection_parts_per_step,
      r.projection_sweeps_per_step);
  std::fflush(stdout);
}

// Ties the throws of `spec` (ParseKnotThrows: "2" double overhand, "1r,1l" square, "1r,1r"
// granny, "2r,1l" surgeon's), pulls, holds 20 mN for 2 s, and reports per phase.
// With `stitch`: around it (KnotStitchDef), a thread of stitch_length_m.
int RunTie(const std::string& spec, int nodes, bool force_limited_pull, double pull_tension_N,
           const KnotStitchDef* stitch, double stitch_length_m, double next_offset_m,
           const std::string& obj, const std::string& json, const ContactOverrides& contact) {
  ThreadDef def = contact.Apply(KnotTyingDef(nodes));
  if (stitch != nullptr) def.length_m = stitch_length_m;
  std::printf(
      "tie %s, %d nodes%s: pull %.3g mN, exact_contact_pairs %d, friction %.3g (thread), %.3g "
      "(objects)\n",
      spec.c_str(), nodes, stitch != nullptr ? ", around a stitch" : "", pull_tension_N * 1e3,
      def.exact_contact_pairs, def.friction_coefficient, def.object_friction_coefficient);
  std::vector<KnotThrowOptions> throws = ParseKnotThrows(spec);
  for (KnotThrowOptions& t : throws) {
    t.force_limited_pull = force_limited_pull;
    t.pull_tension_N = pull_tension_N;
  }
  const TieReport r = RunKnotTie(def, throws, KnotHoldOptions{}, PrintPhase, stitch, next_offset_m);
  std::printf(
      "knot %s (after the pull %s), min distance %.3f d, held %s (knot moved %.3g mm along the "
      "thread), %.0f steps/s (median), tick p99 %.0f us, rolled back %lld, max strain %.4f (hold "
      "%.4f)\n",
      r.knot.c_str(), r.knot_after_pull.c_str(), r.min_distance_over_d, r.held ? "yes" : "no",
      r.hold_shift_m * 1e3, r.steps_per_s, r.tick_p99_us, r.rollbacks, r.max_strain,
      r.max_strain_hold);
  if (!json.empty()) WriteFile(json, TieJson(spec, nodes, def.friction_coefficient, r) + "\n");
  if (!obj.empty() && stitch != nullptr) {
    // Around a stitch: in the tissue's frame, as the stitch-knot recogniser and the knot quiz
    // read it (the surface z = 0 at 0.35 mm under the thread's line, z out of the tissue, the
    // first puncture at x = 0).
    constexpr double kSurfaceY_m = -0.35e-3;
    const double x0 = stitch->x_m - stitch->guide_offset_m;
    std::vector<Eigen::Vector3d> tissue_frame;
    for (int i = 0; i < r.x_final_W.cols(); ++i) {
      const Eigen::Vector3d p = r.x_final_W.col(i);
      tissue_frame.emplace_back(p.x() - x0, -p.z(), p.y() - kSurfaceY_m);
    }
    knot::WriteObjPolyline(
        obj, tissue_frame,
        {"microdex-bench thread --tie " + spec + " --nodes " + std::to_string(nodes) + " --stitch" +
             (force_limited_pull ? " --force-limited-pull" : "") + " --pull-tension " +
             Num(pull_tension_N) + ": " + r.knot,
         "the tissue's frame: surface z = 0, the first puncture at x = 0, metres"},
        def.diameter_m);
  } else if (!obj.empty()) {
    std::ostringstream out;
    out << "o thread\n";
    for (int i = 0; i < r.x_final_W.cols(); ++i) {
      out << "v " << Num(r.x_final_W(0, i)) << " " << Num(r.x_final_W(1, i)) << " "
          << Num(r.x_final_W(2, i)) << "\n";
    }
    out << "l";
    for (int i = 1; i <= r.x_final_W.cols(); ++i) out << " " << i;
    out << "\n";
    WriteFile(obj, out.str());
  }
  return 0;
}

// True when `only` (knot throws separated by ';', empty: all) lists spec.
bool Selected(const std::string& only, const std::string& spec) {
  return only.empty() || (";" + only + ";").find(";" + spec + ";") != std::string::npos;
}

// The matrix of the README: five knots x node counts x thread-on-thread friction, one run each,
// the same script and tensions. Writes the JSON of every run and a markdown table.
int RunTieMatrix(bool quick, const std::string& only, double pull_tension_N,
                 const std::string& json, const std::string& markdown,
                 const ContactOverrides& contact) {
  struct Knot {
    const char* name;
    const char* spec;
    const char* expected;
  };
  const std::vector<Knot> knots = {{"overhand", "1r", "overhand-right"},
                                   {"double overhand", "2r", "double-overhand"},
                                   {"square", "1r,1l", "square"},
                                   {"granny", "1r,1r", "granny"},
                                   {"surgeon's", "2r,1l", "surgeons"}};
  const std::vector<int> nodes =
      quick ? std::vector<int>{129} : std::vector<int>{129, 257, 385, 513};
  const std::vector<double> mus =
      quick ? std::vector<double>{0.2} : std::vector<double>{0.1, 0.2, 0.3};
  std::ostringstream runs, table;
  table << "| knot | nodes | μ | knot after hold | tied + held, ≥ 0.95 d | min distance / d | knot "
           "moved in hold [mm] | max strain tie / hold | capstan: driver / bound | steps/s "
           "(median, whole run) | tick p99 [µs] |\n"
           "|---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|\n";
  int ok = 0, total = 0, capstan_exceeded = 0, two_throw = 0;
  const auto t0 = Clock::now();
  int selected = 0;
  for (const Knot& k : knots) selected += Selected(only, k.spec) ? 1 : 0;
  const int count = static_cast<int>(selected * nodes.size() * mus.size());
  for (const Knot& k : knots) {
    if (!Selected(only, k.spec)) continue;
    for (const int n : nodes) {
      for (const double mu : mus) {
        ContactOverrides c = contact;
        c.friction = mu;
        const ThreadDef def = c.Apply(KnotTyingDef(n));
        std::vector<KnotThrowOptions> throws = ParseKnotThrows(k.spec);
        for (KnotThrowOptions& t : throws) t.pull_tension_N = pull_tension_N;
        const TieReport r = RunKnotTie(def, throws, KnotHoldOptions{});
        const bool good = r.knot == k.expected && r.held && r.min_distance_over_d >= 0.95;
        ok += good ? 1 : 0;
        ++total;
        const double elapsed = Seconds(t0, Clock::now());
        std::printf(
            "[%d/%d, %.0f s, ETA %.0f s] %-15s %3d nodes mu %.1f: %-16s held %-3s min %.3f d "
            "%6.0f steps/s p99 %5.0f us %s\n",
            total, count, elapsed, elapsed / total * (count - total), k.name, n, mu, r.knot.c_str(),
            r.held ? "yes" : "no", r.min_distance_over_d, r.steps_per_s, r.tick_p99_us,
            good ? "ok" : "FAIL");
        std::fflush(stdout);
        runs << (total > 1 ? ",\n  " : "\n  ") << TieJson(k.spec, n, mu, r);
        // The capstan check of thread_knot_tying_test on the second throw's exit.
        std::string capstan = "–";
        if (const TiePhaseReport* exit = SecondThrowExit(r)) {
          const double bound = CapstanBound_N(*exit, mu);
          const bool exceeded = exit->f_driver_max_N > bound;
          char cell[96];
          std::snprintf(cell, sizeof(cell), "%.1f / %.1f mN%s", exit->f_driver_max_N * 1e3,
                        bound * 1e3, exceeded ? " **exceeded**" : "");
          capstan = cell;
          ++two_throw;
          capstan_exceeded += exceeded ? 1 : 0;
        }
        char row[512];
        std::snprintf(row, sizeof(row),
                      "| %s | %d | %.1f | %s | %s | %.3f | %.2f | %.1f %% / %.1f %% | %s | %.0f | "
                      "%.0f |\n",
                      k.name, n, mu, r.knot.c_str(), good ? "yes" : "**NO**", r.min_distance_over_d,
                      r.hold_shift_m * 1e3, 100.0 * r.max_strain, 100.0 * r.max_strain_hold,
                      capstan.c_str(), r.steps_per_s, r.tick_p99_us);
        table << row;
      }
    }
  }
  std::printf(
      "pull %.3g mN: %d of %d tied and held with min distance >= 0.95 d; capstan bound exceeded "
      "in %d of %d two-throw knots\n%s",
      pull_tension_N * 1e3, ok, total, capstan_exceeded, two_throw, table.str().c_str());
  if (!json.empty()) {
    WriteFile(json, "{\"study\": \"tie matrix\", \"pull_tension_N\": " + Num(pull_tension_N) +
                        ", \"runs\": [" + runs.str() + "\n]}\n");
  }
  if (!markdown.empty()) WriteFile(markdown, table.str());
  return ok == total ? 0 : 1;
}

// ---- adversarial -----------------------------------------------------------------------------
// Random, jerky, extreme grasp motion (the CTest ThreadAdversarial at any length): +-2 mm jerks
// per step, 10 cm teleports of each grasp every 5,000 steps, 10 rad roll jumps, tools moved to
// random nodes every 7,919 steps; then the thread is let go by one tool and must return to its
// rest length (strain < 1 %).
int RunAdversarial(std::int64_t steps, const std::string& json) {
  ThreadDef def = StiffNylon10_0();
  def.num_nodes = 33;
  def.length_m = 0.015;
  const ThreadModel model = MakeThreadModel(def);
  ThreadState state =
      MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> node(0, model.num_nodes - 1);
  int slots[2] = {GraspNode(model, 0, state), GraspNode(model, model.num_nodes - 1, state)};
  const std::vector<Collider> colliders = {
      Collider::Plane(Eigen::Vector3d(0, 0, -0.002), Eigen::Vector3d::UnitZ()),
      Collider::Sphere(Eigen::Vector3d(0.007, 0.0, 0.0), 0.001)};
  std::int64_t nonfinite_states = 0, nonfinite_forces = 0, teleports = 0;
  double max_force = 0.0;
  const auto t0 = Clock::now();
  for (std::int64_t k = 0; k < steps; ++k) {
    for (int s = 0; s < 2; ++s) {
      Grasp& g = state.grasps[slots[s]];
      Eigen::Vector3d p = g.p_WT + 2e-3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      if (k % 5000 == 2500 * s) {
        p += 0.1 * Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
        ++teleports;
      }
      p = p.cwiseMax(-0.2).cwiseMin(0.2);
      SetGraspTarget(state, slots[s], p, 10.0 * u(rng));
    }
    if (k % 7919 == 0) {
      const int s = static_cast<int>(k % 2);
      ReleaseGrasp(state, slots[s]);
      slots[s] = GraspNode(model, node(rng), state);
    }
    StepThread(model, colliders, ws, state);
    if (!state.x_W.allFinite() || !state.v_W.allFinite() || !state.q_rad.allFinite()) {
      ++nonfinite_states;
    }
    for (int s = 0; s < 2; ++s) {
      const Eigen::Vector3d f = GraspForce(state, slots[s], 10.0);
      if (!f.allFinite()) ++nonfinite_forces;
      max_force = std::max(max_force, f.norm());
    }
  }
  const double seconds = Seconds(t0, Clock::now());
  ReleaseGrasp(state, slots[1]);
  int recovered_at = -1;
  for (int k = 0; k < 2000; ++k) {
    StepThread(model, colliders, ws, state);
    if (CalcMaxStrain(model, state.x_W) < 0.01) {
      recovered_at = k + 1;
      break;
    }
  }
  const long long rollbacks = state.status.nonfinite_resets + state.status.factorization_failures;
  std::printf(
      "adversarial: %lld steps (%.1f s simulated, %.1f s wall, %.0f steps/s), %lld teleports\n"
      "non-finite states %lld, non-finite tool forces %lld, rolled-back steps %lld, largest "
      "saturated tool force %.3g N\nrest length (strain < 1 %%) recovered %s%.3f s after "
      "letting go\n",
      static_cast<long long>(steps), steps * def.time_step_s, seconds, steps / seconds,
      static_cast<long long>(teleports), static_cast<long long>(nonfinite_states),
      static_cast<long long>(nonfinite_forces), rollbacks, max_force,
      recovered_at > 0 ? "" : "NOT within 2 s; ",
      (recovered_at > 0 ? recovered_at : 2000) * def.time_step_s);
  if (!json.empty()) {
    std::ostringstream out;
    out << "{\n  \"study\": \"adversarial\",\n  \"steps\": " << steps
        << ",\n  \"teleports\": " << teleports << ",\n  \"nonfinite_states\": " << nonfinite_states
        << ",\n  \"nonfinite_tool_forces\": " << nonfinite_forces
        << ",\n  \"rolled_back_steps\": " << rollbacks
        << ",\n  \"max_tool_force_N\": " << Num(max_force)
        << ",\n  \"recovered\": " << (recovered_at > 0 ? "true" : "false")
        << ",\n  \"recovery_s\": " << Num(recovered_at > 0 ? recovered_at * def.time_step_s : NAN)
        << ",\n  \"steps_per_s\": " << Num(steps / seconds) << "\n}\n";
    WriteFile(json, out.str());
  }
  return nonfinite_states == 0 && nonfinite_forces == 0 && recovered_at > 0 ? 0 : 1;
}

int Main(int argc, char** argv) {
  bool stability = false, accuracy = false, quick = false, adversarial = false, stitch = false;
  bool force_limited_pull = false;
  KnotStitchDef stitch_def;
  double stitch_length_m = 18e-3;
  double next_offset_m = 3e-3;
  std::int64_t steps = 1000000;
  int nodes = 257;
  bool tie_matrix = false;
  std::string json, plot, tie, obj, markdown, only;
  double pull_tension_N = kTieMatrixPullTension_N;
  ContactOverrides contact;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(std::string(name) + ": expected a value");
      return argv[++i];
    };
    if (arg == "--stability") {
      stability = true;
    } else if (arg == "--force-limited-pull") {
      force_limited_pull = true;
    } else if (arg == "--accuracy") {
      accuracy = true;
    } else if (arg == "--adversarial") {
      adversarial = true;
    } else if (arg == "--steps") {
      steps = std::atoll(value("--steps").c_str());
      if (steps < 1) throw std::invalid_argument("--steps: expected a positive count");
    } else if (arg == "--quick") {
      quick = true;
    } else if (arg == "--obj") {
      obj = value("--obj");
    } else if (arg == "--json") {
      json = value("--json");
    } else if (arg == "--plot") {
      plot = value("--plot");
    } else if (arg == "--tie") {
      tie = value("--tie");
    } else if (arg == "--stitch") {
      stitch = true;
    } else if (arg == "--stitch-geometry") {
      // x_m,depth_m,guide_offset_m,rod_radius_m,guide_radius_m,start_x_m,length_m (mm)
      std::istringstream in(value("--stitch-geometry"));
      std::vector<double> v;
      for (std::string item; std::getline(in, item, ',');)
        v.push_back(std::atof(item.c_str()) * 1e-3);
      if (v.size() != 7) throw std::invalid_argument("--stitch-geometry: expected 7 numbers (mm)");
      stitch_def = {v[0], v[1], v[2], v[3], v[4], v[5]};
      stitch_def.Validate();
      stitch_length_m = v[6];
      stitch = true;
    } else if (arg == "--next-throw-offset") {
      next_offset_m = std::atof(value("--next-throw-offset").c_str()) * 1e-3;
      if (!(next_offset_m > 0.0 && next_offset_m < 20e-3)) {
        throw std::invalid_argument("--next-throw-offset: expected a distance in (0, 20) mm");
      }
    } else if (arg == "--tie-matrix") {
      tie_matrix = true;
    } else if (arg == "--only") {
      only = value("--only");
    } else if (arg == "--pull-tension") {
      pull_tension_N = std::atof(value("--pull-tension").c_str());
      if (!(pull_tension_N > 0.0 && pull_tension_N < 1.0)) {
        throw std::invalid_argument("--pull-tension: expected a tension in (0, 1) N");
      }
    } else if (arg == "--markdown") {
      markdown = value("--markdown");
    } else if (arg == "--friction") {
      contact.friction = std::atof(value("--friction").c_str());
      if (!(contact.friction >= 0.0)) throw std::invalid_argument("--friction: expected mu >= 0");
    } else if (arg == "--object-friction") {
      contact.object_friction = std::atof(value("--object-friction").c_str());
      if (!(contact.object_friction >= 0.0)) {
        throw std::invalid_argument("--object-friction: expected mu >= 0");
      }
    } else if (arg == "--contact-force") {
      contact.contact_force = std::atof(value("--contact-force").c_str());
      if (!(contact.contact_force >= 0.0)) {
        throw std::invalid_argument("--contact-force: expected a force >= 0 N");
      }
    } else if (arg == "--friction-contacts") {
      contact.friction_contacts = std::atoi(value("--friction-contacts").c_str());
      if (contact.friction_contacts < 0) {
        throw std::invalid_argument("--friction-contacts: expected N >= 0");
      }
    } else if (arg == "--friction-self-contacts") {
      contact.friction_self_contacts = std::atoi(value("--friction-self-contacts").c_str());
      if (contact.friction_self_contacts < 0) {
        throw std::invalid_argument("--friction-self-contacts: expected N >= 0");
      }
    } else if (arg == "--exact-pairs") {
      contact.exact_pairs = std::atoi(value("--exact-pairs").c_str());
      if (contact.exact_pairs < 0) throw std::invalid_argument("--exact-pairs: expected N >= 0");
    } else if (arg == "--nodes") {
      nodes = std::atoi(value("--nodes").c_str());
      if (nodes < 33) throw std::invalid_argument("--nodes: expected at least 33");
    } else if (arg == "--help" || arg == "-h") {
      std::printf(
          "microdex-bench thread [--stability [--plot FILE.png] | --accuracy | --adversarial "
          "[--steps N] | --tie THROWS "
          "[--nodes N] [--stitch] [--next-throw-offset MM (default 3)] [--obj FILE] | --tie-matrix "
          "[--only SPEC;SPEC] [--markdown "
          "FILE]] [--pull-tension N (default 0.015)] "
          "[--friction MU] "
          "[--object-friction MU] [--exact-pairs N] [--friction-contacts N] "
          "[--friction-self-contacts N] "
          "[--json FILE] [--quick]\n");
      return 0;
    } else {
      throw std::invalid_argument("unknown option '" + arg + "'");
    }
  }
  if (!tie.empty()) {
    return RunTie(tie, nodes, force_limited_pull, pull_tension_N, stitch ? &stitch_def : nullptr,
                  stitch_length_m, next_offset_m, obj, json, contact);
  }
  if (tie_matrix) return RunTieMatrix(quick, only, pull_tension_N, json, markdown, contact);
  if (stability) return RunStability(quick, json, plot);
  if (adversarial) return RunAdversarial(quick ? 20000 : steps, json);
  if (accuracy) return RunAccuracy(quick, json);
  return RunSpeed(quick, json, contact);
}

}  // namespace
}  // namespace microdex::thread

MICRODEX_REGISTER_BENCH(thread, "thread",
                        "suture thread: --stability, --accuracy, speed during knot tying",
                        microdex::thread::Main);
