#include "common/thread/thread_scenarios.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/base/check.h"
#include "common/thread/grasp.h"
#include "common/thread/thread_contacts.h"
#include "common/thread/thread_forces.h"
#include "common/thread/thread_step.h"

namespace microdex::thread {
namespace {

double SmoothStep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
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
  const int slot_fixed = GraspNode(model, 0, state);
  const int slot_end = GraspNode(model, model.num_nodes - 1, state);
  MICRODEX_CHECK(slot_fixed >= 0 && slot_end >= 0);
  const double rod_r = 1e-3;
  const std::vector<Collider> colliders = {Collider::Capsule(
      Eigen::Vector3d(0.02, -0.02, -0.012), Eigen::Vector3d(0.02, 0.02, -0.012), rod_r)};

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
    StepThreadWith(model, options.integrator, h, colliders, state);
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
    for (int j = 0; j < model.num_links; ++j) {
      const LinkColliderGap gap =
          CalcLinkColliderGap(colliders[0], state.x_W.col(j), state.x_W.col(j + 1), model.radius_m);
      if (gap.gap_m < -model.radius_m) report.no_tunnelling = false;
    }
    if (CalcMinNonAdjacentDistance(model, state.x_W) < min_self_m) report.no_tunnelling = false;
    if (k % sample_every == 0) report.samples.push_back(state.x_W);
    if (options.stop_when_unstable && !report.stable()) break;
  }
  return report;
}

ThreadDef KnotTyingDef(int num_nodes) {
  ThreadDef def = StiffNylon10_0();
  def.name = "knot-tying-nylon";
  const double link_m = def.length_m / (def.num_nodes - 1);
  def.num_nodes = num_nodes;
  def.length_m = link_m * (num_nodes - 1);
  def.gravity_m_per_s2.setZero();
  return def;
}

namespace {

// Jig geometry, m. The loop is held by four pegs around (x_c, kJigY); the working end passes
// kOver above or below the table plane to cross over or under a strand.
constexpr double kJigHalf = 1.5e-3;
constexpr double kJigY = 4e-3;
constexpr double kAround = 2e-3;  // the end's path runs this far outside the pegs
constexpr double kPegRadius = 0.25e-3;
constexpr double kPegHeight = 5e-3;
constexpr double kOver = 0.6e-3;

}  // namespace

KnotTyingScript::KnotTyingScript(const ThreadModel& model, ThreadState& state,
                                 const KnotTieOptions& options)
    : options_(options) {
  const double length = model.def.length_m;
  const double a = kJigHalf;
  const double out = a + kAround;
  const double z = options.mirror ? -kOver : kOver;
  // The thread is laid unknotted: along +x to the jig, up its right side, across its top and
  // down its left side, so that the end starts above the standing part.
  const double tail = (kJigY + out) + 2.0 * out + (out - 0.3e-3);
  const double x_c = std::min(options.jig_x_fraction * length, length - tail - out);
  const Eigen::Vector3d v[5] = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(x_c + out, 0, 0),
                                Eigen::Vector3d(x_c + out, kJigY + out, 0),
                                Eigen::Vector3d(x_c - out, kJigY + out, 0),
                                Eigen::Vector3d(x_c - out, 0.3e-3, 0)};
  // Place nodes at rest spacing along the polyline, starting so that it ends at v[4].
  double poly = 0.0;
  for (int k = 0; k < 4; ++k) poly += (v[k + 1] - v[k]).norm();
  const double start = poly - length;  // may be negative: extend the first segment backwards
  for (int i = 0; i < model.num_nodes; ++i) {
    double s = start + i * model.rest_length_m[0];
    Eigen::Vector3d p;
    if (s <= 0.0) {
      p = v[0] + s * Eigen::Vector3d::UnitX();
    } else {
      int k = 0;
      while (k < 3 && s > (v[k + 1] - v[k]).norm()) {
        s -= (v[k + 1] - v[k]).norm();
        ++k;
      }
      p = v[k] + s * (v[k + 1] - v[k]).normalized();
    }
    state.x_W.col(i) = p;
  }
  state.v_W.setZero();
  slot_b_ = GraspNode(model, 0, state);
  slot_a_ = GraspNode(model, model.num_nodes - 1, state);
  MICRODEX_CHECK(slot_a_ >= 0 && slot_b_ >= 0);
  for (double sx : {-1.0, 1.0}) {
    for (double sy : {-1.0, 1.0}) {
      const Eigen::Vector3d c(x_c + sx * a, kJigY + sy * a, 0.0);
      colliders_.push_back(Collider::Capsule(c - kPegHeight * Eigen::Vector3d::UnitZ(),
                                             c + kPegHeight * Eigen::Vector3d::UnitZ(),
                                             kPegRadius));
    }
  }
  // The working end's path: over the standing part, over the loop's near edge, down through
  // the loop, out under its far edge; once more for a double overhand; then away.
  std::vector<Eigen::Vector3d> path = {
      state.x_W.col(model.num_nodes - 1), Eigen::Vector3d(x_c - out, -1.2e-3, z),
      Eigen::Vector3d(x_c, -1.2e-3, z),   Eigen::Vector3d(x_c, kJigY, z),
      Eigen::Vector3d(x_c, kJigY, -z),    Eigen::Vector3d(x_c + out + 1e-3, kJigY, -z),
  };
  for (int pass = 1; pass < options.passes; ++pass) {
    const double dy = 0.6e-3 * pass;
    path.push_back(Eigen::Vector3d(x_c + out + 1e-3, kJigY + dy, z));
    path.push_back(Eigen::Vector3d(x_c, kJigY + dy, z));
    path.push_back(Eigen::Vector3d(x_c, kJigY + dy, -z));
    path.push_back(Eigen::Vector3d(x_c + out + 1e-3, kJigY + dy, -z));
  }
  path.push_back(Eigen::Vector3d(x_c + out + 4e-3, kJigY, 0.0));
  // The standing end feeds thread as the working end uses it.
  const Eigen::Vector3d b0 = state.x_W.col(0);
  double so_far = 0.0;
  for (size_t k = 0; k < path.size(); ++k) {
    if (k > 0) so_far += (path[k] - path[k - 1]).norm();
    const double feed = std::min(0.8 * so_far, std::max(0.0, x_c - out - b0.x() - 2e-3));
    waypoints_.push_back({path[k], b0 + feed * Eigen::Vector3d::UnitX(), true, false});
  }
  // Pull: pegs out, the grasps move apart along x.
  Waypoint pull = waypoints_.back();
  pull.pegs_enabled = false;
  pull.pull = true;
  waypoints_.push_back(pull);
}

bool KnotTyingScript::Step(const ThreadModel& model, ThreadState& state) {
  if (done_) return false;
  const double h = model.def.time_step_s;
  const Waypoint& from = waypoints_[segment_];
  if (segment_ + 1 >= static_cast<int>(waypoints_.size())) {
    done_ = true;
    return false;
  }
  const Waypoint& to = waypoints_[segment_ + 1];
  for (Collider& c : colliders_) c.enabled = to.pegs_enabled;
  if (to.pull) {
    const double dx = options_.pull_speed_m_per_s * h;
    pulled_m_ += dx;
    const Eigen::Vector3d pa = state.grasps[slot_a_].p_WT + dx * Eigen::Vector3d::UnitX();
    const Eigen::Vector3d pb = state.grasps[slot_b_].p_WT - dx * Eigen::Vector3d::UnitX();
    SetGraspTarget(state, slot_a_, pa, 0.0);
    SetGraspTarget(state, slot_b_, pb, 0.0);
    StepThread(model, colliders_, state);
    const double fa = state.grasps[slot_a_].f_T_W.norm();
    const double fb = state.grasps[slot_b_].f_T_W.norm();
    if ((fa > options_.pull_tension_N && fb > options_.pull_tension_N) ||
        pulled_m_ >= options_.max_pull_m) {
      done_ = true;
    }
    return !done_;
  }
  const double seg_len = std::max((to.p_a_W - from.p_a_W).norm(), 1e-12);
  segment_s_ += options_.speed_m_per_s * h;
  const double u = std::min(segment_s_ / seg_len, 1.0);
  SetGraspTarget(state, slot_a_, from.p_a_W + u * (to.p_a_W - from.p_a_W), 0.0);
  SetGraspTarget(state, slot_b_, from.p_b_W + u * (to.p_b_W - from.p_b_W), 0.0);
  StepThread(model, colliders_, state);
  if (u >= 1.0) {
    ++segment_;
    segment_s_ = 0.0;
  }
  return true;
}

}  // namespace microdex::thread
