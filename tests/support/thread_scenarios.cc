#include "tests/support/thread_scenarios.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "common/base/check.h"
#include "common/geometry/segment_distance.h"
#include "common/knot/recognition.h"
#include "common/thread/grasp.h"
#include "common/thread/thread_contacts.h"
#include "common/thread/thread_forces.h"
#include "common/thread/thread_step.h"

namespace microdex::thread {
namespace {

// Quintic blend 6u^5 - 15u^4 + 10u^3: velocity and acceleration vanish at both ends, so the
// keyframed grasp motion is C2 (a cubic blend is only C1: its acceleration jumps at every key
// and excites the stiff stretch vibrations, which the accuracy study must not depend on).
double SmoothStep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (u * (6.0 * u - 15.0) + 10.0);
}

// Swing-and-pull keyframes of the grasped end (time s, position m).
struct Key {
  double t_s;
  Eigen::Vector3d p_W;
};

Eigen::Vector3d SwingPullTarget(double t_s) {
  static const Key kKeys[] = {
      {0.00, {0.050, 0.0, 0.000}},  {0.20, {0.030, 0.0, -0.025}},  {0.40, {0.045, 0.0, 0.015}},
      {0.60, {-0.020, 0.0, 0.040}}, {0.80, {-0.040, 0.0, -0.015}}, {1.00, {-0.047, 0.0, 0.010}},
  };
  constexpr int kNum = sizeof(kKeys) / sizeof(kKeys[0]);
  if (t_s <= kKeys[0].t_s) return kKeys[0].p_W;
  for (int k = 0; k + 1 < kNum; ++k) {
    if (t_s <= kKeys[k + 1].t_s) {
      const double u = (t_s - kKeys[k].t_s) / (kKeys[k + 1].t_s - kKeys[k].t_s);
      return kKeys[k].p_W + SmoothStep(u) * (kKeys[k + 1].p_W - kKeys[k].p_W);
    }
  }
  return kKeys[kNum - 1].p_W;
}

}  // namespace

ThreadDef SwingPullDef(double stretch_N_per_m, double bend_N_m, double node_mass_kg) {
  ThreadDef def;
  def.name = "swing-pull";
  def.num_nodes = 33;
  def.length_m = 0.05;
  def.diameter_m = 0.3e-3;
  def.stretch_stiffness_N_per_m = stretch_N_per_m;
  def.bend_stiffness_N_m = bend_N_m;
  def.twist_stiffness_N_m = bend_N_m;
  def.node_mass_kg = node_mass_kg;
  def.drag_N_s_per_m2 = 1e-3;
  def.twist_drag_N_m_s = 1e-12;
  def.contact_damping_N_s_per_m = 1e-4;
  def.contact_force_N = 1e-2;
  def.contact_decay_m = 30e-6;
  def.contact_cutoff_m = 150e-6;
  def.twist_coupling_N = 0.0;
  return def;
}

SwingPullReport RunSwingPull(const ThreadDef& def, const SwingPullOptions& options) {
  const ThreadModel model = MakeThreadModel(def);
  ThreadState state =
      MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  const int slot_fixed = GraspNode(model, 0, state);
  const int slot_end = GraspNode(model, model.num_nodes - 1, state);
  MICRODEX_CHECK(slot_fixed >= 0 && slot_end >= 0);
  const double rod_r = 1e-3;
  std::vector<Collider> colliders;
  if (options.rod) {
    colliders.push_back(Collider::Capsule(Eigen::Vector3d(0.02, -0.02, -0.012),
                                          Eigen::Vector3d(0.02, 0.02, -0.012), rod_r));
  }

  SwingPullReport report;
  double total_mass = model.mass_kg.sum();
  const double g = def.gravity_m_per_s2.norm();
  const double v_ref = 1.0;  // the end moves at up to ~0.6 m/s
  report.energy_bound_J =
      100.0 * (0.5 * total_mass * v_ref * v_ref + total_mass * g * def.length_m +
               model.num_links * 0.5 * model.stretch_k_N_per_m[0] *
                   std::pow(0.1 * model.rest_length_m[0], 2) +
               model.num_nodes * 0.5 * model.bend_k_N_m.maxCoeff());
  const double h = options.time_step_s;
  const int steps = static_cast<int>(std::lround(options.duration_s / h));
  const int sample_every = std::max(1, static_cast<int>(std::lround(options.sample_period_s / h)));
  const double min_self_m = 0.5 * def.diameter_m;
  report.samples.push_back(state.x_W);
  for (int k = 1; k <= steps; ++k) {
    SetGraspTarget(state, slot_end, SwingPullTarget(k * h), 0.0);
    const std::int64_t trouble_before =
        state.status.nonfinite_resets + state.status.factorization_failures;
    StepThreadWith(model, options.integrator, h, colliders, ws, state);
    ++report.steps;
    if (state.status.nonfinite_resets + state.status.factorization_failures > trouble_before) {
      report.finite = false;
    }
    report.max_strain = std::max(report.max_strain, state.status.max_strain);
    if (!(state.status.max_strain < 0.1)) report.strain_ok = false;
    const double energy = CalcKineticEnergy(model, state) + CalcStretchEnergy(model, state.x_W) +
                          CalcBendEnergy(model, state.x_W) + CalcTwistEnergy(model, state.q_rad);
    if (!std::isfinite(energy)) report.finite = false;
    report.max_energy_J = std::max(report.max_energy_J, energy);
    if (!(energy <= report.energy_bound_J)) report.energy_bounded = false;
    for (int j = 0; j < model.num_links && options.rod; ++j) {
      const LinkColliderGap gap =
          CalcLinkColliderGap(colliders[0], state.x_W.col(j), state.x_W.col(j + 1), model.radius_m);
      if (gap.gap_m < -model.radius_m) report.no_tunnelling = false;
    }
    report.max_self_contacts = std::max(report.max_self_contacts, state.status.num_self_contacts);
    report.max_object_contacts =
        std::max(report.max_object_contacts, state.status.num_object_contacts);
    if (CalcMinNonAdjacentDistance(model, state.x_W) < min_self_m) report.no_tunnelling = false;
    if (k % sample_every == 0) report.samples.push_back(state.x_W);
    if (options.stop_when_unstable && !report.stable()) break;
  }
  return report;
}

ThreadDef KnotTyingDef(int num_nodes) {
  ThreadDef def = StiffNylon10_0();
  def.name = "knot-tying-nylon";
  constexpr double kMinLength_m = 12.8e-3;
  const double link_m = std::max(2.0 * def.diameter_m, kMinLength_m / (num_nodes - 1));
  def.num_nodes = num_nodes;
  def.length_m = link_m * (num_nodes - 1);
  def.gravity_m_per_s2.setZero();
  // Thread on thread keeps the nylon's friction; the jig's pegs and jaws are frictionless (wet,
  // polished instruments): the driver carries the end round them by position, so with peg
  // friction the thread it needs is drawn over ~5 pi of wrap (capstan factor e^{0.2 * 5 pi} =
  // 23) and the driver's pull reaches ~40 mN with 15 % transient strain in the helix.
  def.object_friction_coefficient = 0.0;
  return def;
}

std::vector<Collider> FoldIntoUOverACapsule(const ThreadModel& model, ThreadState& state) {
  MICRODEX_CHECK(model.num_nodes == 65);
  state = MakeStraightThreadState(model, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  for (int i = 33; i < model.num_nodes; ++i) {
    state.x_W.col(i) = Eigen::Vector3d(state.x_W(0, 64 - i), 30e-6, 0.0);
  }
  return {Collider::Capsule(Eigen::Vector3d(0.005, -0.01, -40e-6),
                            Eigen::Vector3d(0.005, 0.01, -40e-6), 20e-6)};
}

KnotTyingHands SetUpKnotTying(const ThreadModel& model, ThreadState& state) {
  for (Grasp& g : state.grasps) {
    if (g.node >= 0) ReleaseGrasp(state, static_cast<int>(&g - state.grasps.data()));
  }
  double s_m = 0.0;
  for (int i = 0; i < model.num_nodes; ++i) {
    state.x_W.col(i) = Eigen::Vector3d(s_m, 0.0, 0.0);
    if (i < model.num_links) s_m += model.rest_length_m[i];
  }
  state.v_W.setZero();
  state.q_rad.setZero();
  state.qdot_rad_per_s.setZero();
  KnotTyingHands hands;
  hands.standing_slot = GraspNode(model, 0, state);
  hands.driver_slot = GraspNode(model, model.num_nodes - 1, state);
  MICRODEX_CHECK(hands.standing_slot >= 0 && hands.driver_slot >= 0);
  return hands;
}

double BruteForceMinDistance(const Eigen::Matrix3Xd& x, double limit_m) {
  const int links = static_cast<int>(x.cols()) - 1;
  std::vector<Eigen::Vector3d> mid(std::max(0, links));
  std::vector<double> half(std::max(0, links));
  for (int j = 0; j < links; ++j) {
    mid[j] = 0.5 * (x.col(j) + x.col(j + 1));
    half[j] = 0.5 * (x.col(j + 1) - x.col(j)).norm();
  }
  double best = limit_m;
  for (int a = 0; a < links; ++a) {
    for (int b = a + 2; b < links; ++b) {
      const double reach = half[a] + half[b] + best;
      if ((mid[a] - mid[b]).squaredNorm() >= reach * reach) continue;
      const geometry::SegmentClosest c =
          geometry::ClosestSegmentSegment(x.col(a), x.col(a + 1), x.col(b), x.col(b + 1));
      best = std::min(best, c.distance_m);
    }
  }
  return best;
}

namespace {

const char* PhaseWord(KnotThrowScript::Phase phase) {
  switch (phase) {
    case KnotThrowScript::Phase::kLoop:
      return "loop";
    case KnotThrowScript::Phase::kHelix:
      return "helix";
    case KnotThrowScript::Phase::kExit:
      return "exit";
    case KnotThrowScript::Phase::kRelease:
      return "release";
    case KnotThrowScript::Phase::kPull:
      return "pull";
    case KnotThrowScript::Phase::kDone:
      return "done";
  }
  return "?";
}

knot::KnotAnalysis AnalyzeThread(const ThreadModel& model, const ThreadState& state, bool locate) {
  std::vector<Eigen::Vector3d> poly(model.num_nodes);
  for (int i = 0; i < model.num_nodes; ++i) poly[i] = state.x_W.col(i);
  knot::KnotOptions options;
  options.thread_diameter_m = model.def.diameter_m;
  options.locate = locate;
  return knot::AnalyzeKnot(poly, options);
}

// Step times and distances of one phase.
struct PhaseMeter {
  std::vector<double> step_us;
  TiePhaseReport report;
  std::int64_t pair_tests_seen = 0;    // the state's count at the last step measured
  std::int64_t pair_tests = 0;         // in this phase
  std::int64_t parts = 0, sweeps = 0;  // the projection's, in this phase
  void Start(int throw_index, const char* phase) {
    step_us.clear();
    pair_tests = 0;
    parts = 0;
    sweeps = 0;
    report = TiePhaseReport{};
    report.throw_index = throw_index;
    report.phase = phase;
    report.min_distance_over_d = std::numeric_limits<double>::infinity();
  }
  void Add(double us, double d_over_d, const ThreadState& state, const ThreadWorkspace* ws,
           const KnotTyingHands& hands) {
    step_us.push_back(us);
    ++report.steps;
    pair_tests += state.status.pair_tests - pair_tests_seen;
    pair_tests_seen = state.status.pair_tests;
    report.pair_tests_per_step = static_cast<double>(pair_tests) / report.steps;
    report.min_distance_over_d = std::min(report.min_distance_over_d, d_over_d);
    report.max_self_contacts = std::max(report.max_self_contacts, state.status.num_self_contacts);
    if (ws != nullptr) {
      report.max_projection_sweeps = std::max(report.max_projection_sweeps, ws->projection_sweeps);
      parts += ws->projection_parts;
      sweeps += ws->projection_sweeps_total;
      report.projection_parts_per_step = static_cast<double>(parts) / report.steps;
      report.projection_sweeps_per_step = static_cast<double>(sweeps) / report.steps;
      report.max_projection_residual_over_d =
          std::max(report.max_projection_residual_over_d, ws->projection_residual_m);
    }
    report.f_standing_max_N =
        std::max(report.f_standing_max_N, state.grasps[hands.standing_slot].f_T_W.norm());
    report.f_driver_max_N =
        std::max(report.f_driver_max_N, state.grasps[hands.driver_slot].f_T_W.norm());
  }
  TiePhaseReport Finish(const ThreadModel& model, const ThreadState& state) {
    std::vector<double> v = step_us;
    std::sort(v.begin(), v.end());
    if (!v.empty()) {
      const size_t m = v.size() / 2;
      const double median = v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
      report.steps_per_s = 1e6 / median;
      report.tick_p99_us =
          v[std::min(v.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(v.size())))];
    }
    report.knot = std::string(knot::KnotName(AnalyzeThread(model, state, false).type));
    report.max_projection_residual_over_d /= model.def.diameter_m;
    return report;
  }
};

}  // namespace

const TiePhaseReport* SecondThrowExit(const TieReport& r) {
  for (const TiePhaseReport& p : r.phases) {
    if (p.phase == "exit" && p.throw_index == 2) return &p;
  }
  return nullptr;
}

double CapstanBound_N(const TiePhaseReport& exit, double friction) {
  return std::exp(friction * 3.0 * std::numbers::pi) * exit.f_standing_max_N;
}

TieReport RunKnotTie(const ThreadDef& def, std::vector<KnotThrowOptions> throws,
                     KnotHoldOptions hold, void (*on_phase)(const TiePhaseReport&),
                     const KnotStitchDef* stitch, double next_offset_m) {
  using Clock = std::chrono::steady_clock;
  const ThreadModel model = MakeThreadModel(def);
  ThreadState state = stitch != nullptr ? stitch->Lay(model)
                                        : MakeStraightThreadState(model, Eigen::Vector3d::Zero(),
                                                                  Eigen::Vector3d::UnitX());
  KnotTyingHands hands;
  if (stitch != nullptr) {
    hands.standing_slot = GraspNode(model, 0, state);
    hands.driver_slot = GraspNode(model, model.num_nodes - 1, state);
    const std::vector<Collider> rods = stitch->Colliders(model.radius_m);
    for (KnotThrowOptions& t : throws) t.fixed_colliders = rods;
    hold.fixed_colliders = rods;
  } else {
    hands = SetUpKnotTying(model, state);
  }
  TieReport out;
  out.min_distance_over_d = std::numeric_limits<double>::infinity();
  out.pulled_tight = true;
  const double d = model.def.diameter_m;
  const long long trouble0 = state.status.nonfinite_resets + state.status.factorization_failures;
  std::vector<double> all_us;
  PhaseMeter meter;
  meter.pair_tests_seen = state.status.pair_tests;
  auto finish_phase = [&] {
    const TiePhaseReport r = meter.Finish(model, state);
    all_us.insert(all_us.end(), meter.step_us.begin(), meter.step_us.end());
    out.min_distance_over_d = std::min(out.min_distance_over_d, r.min_distance_over_d);
    out.phases.push_back(r);
    if (on_phase != nullptr) on_phase(r);
  };
  // Diagnosis: MICRODEX_TIE_TRACE set prints every step of the throws (knot, largest node move).
  const char* trace = std::getenv("MICRODEX_TIE_TRACE");
  double knot_x = 4e-3;
  for (size_t t = 0; t < throws.size(); ++t) {
    throws[t].knot_x_m = knot_x;
    KnotThrowScript script(model, state, hands, throws[t]);
    ThreadWorkspace ws = MakeThreadWorkspace(model);
    KnotThrowScript::Phase last = script.phase();
    meter.Start(static_cast<int>(t) + 1, PhaseWord(last));
    while (true) {
      const Clock::time_point t0 = Clock::now();
      const bool more = script.Step(model, ws, state);
      const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
      if (script.phase() != last && script.phase() != KnotThrowScript::Phase::kDone) {
        finish_phase();
        last = script.phase();
        meter.Start(static_cast<int>(t) + 1, PhaseWord(last));
      }
      meter.Add(us, BruteForceMinDistance(state.x_W, d) / d, state, &ws, hands);
      if (trace != nullptr) {
        const Eigen::Matrix3Xd& x0 = ws.x_prev_W;
        std::printf(
            "trace %zu %s %d knot %s move %.3f d contacts %d pairs %d sweeps %d strain %.3f\n",
            t + 1, PhaseWord(script.phase()), meter.report.steps,
            std::string(knot::KnotName(AnalyzeThread(model, state, false).type)).c_str(),
            (state.x_W - x0).colwise().norm().maxCoeff() / d, state.status.num_self_contacts,
            state.status.num_candidate_pairs, ws.projection_sweeps, state.status.max_strain);
      }
      out.max_strain = std::max(out.max_strain, state.status.max_strain);
      if (!more) break;
    }
    finish_phase();
    out.pulled_tight = out.pulled_tight && std::min(state.grasps[hands.standing_slot].f_T_W.norm(),
                                                    state.grasps[hands.driver_slot].f_T_W.norm()) >=
                                               throws[t].pull_tension_N;
    // The next throw is tied by the other hand, next_offset_m beyond this knot on its side.
    const knot::KnotAnalysis a = AnalyzeThread(model, state, true);
    std::swap(hands.standing_slot, hands.driver_slot);
    const double side = state.grasps[hands.driver_slot].p_WT.x() >= knot_x ? 1.0 : -1.0;
    knot_x = (a.located ? a.p_core_W.x() : knot_x) + side * next_offset_m;
  }
  const knot::KnotAnalysis before = AnalyzeThread(model, state, true);
  out.knot_after_pull = std::string(knot::KnotName(before.type));
  KnotHoldScript hold_script(model, state, hands, hold);
  ThreadWorkspace hold_ws = MakeThreadWorkspace(model);
  meter.Start(0, "hold");
  while (true) {
    const Clock::time_point t0 = Clock::now();
    const bool more = hold_script.Step(model, hold_ws, state);
    const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    meter.Add(us, BruteForceMinDistance(state.x_W, d) / d, state, &hold_ws, hands);
    out.max_strain_hold = std::max(out.max_strain_hold, state.status.max_strain);
    if (!more) break;
  }
  finish_phase();
  const knot::KnotAnalysis after = AnalyzeThread(model, state, true);
  out.knot = std::string(knot::KnotName(after.type));
  const double s_before = 0.5 * (before.core_start_s_m + before.core_end_s_m);
  const double s_after = 0.5 * (after.core_start_s_m + after.core_end_s_m);
  out.hold_shift_m = before.located && after.located ? std::abs(s_after - s_before)
                                                     : std::numeric_limits<double>::infinity();
  constexpr double kHoldShift_m = 1e-3;
  out.held = before.type == after.type && before.type != knot::KnotType::kNone &&
             before.type != knot::KnotType::kUnknown && out.hold_shift_m < kHoldShift_m;
  std::sort(all_us.begin(), all_us.end());
  if (!all_us.empty()) {
    out.steps_per_s = 1e6 / all_us[all_us.size() / 2];
    out.tick_p99_us = all_us[std::min(
        all_us.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(all_us.size())))];
  }
  out.rollbacks = state.status.nonfinite_resets + state.status.factorization_failures - trouble0;
  out.x_final_W = state.x_W;
  return out;
}

}  // namespace microdex::thread
