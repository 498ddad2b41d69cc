#include "common/thread/knot_tie.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "common/base/check.h"
#include "common/thread/grasp.h"
#include "common/thread/thread_step.h"

namespace microdex::thread {
namespace {

// Jig geometry, m: half the distance between the two pegs, peg radius and half height, the
// clearance of the driver's path around a peg, the helix radius around the standing part and
// the height of the second peg above the standing part.
constexpr double kJigHalf_m = 1.0e-3;
constexpr double kPegRadius_m = 0.1e-3;
constexpr double kPegHalfHeight_m = 1.5e-3;
constexpr double kAround_m = 0.3e-3;
constexpr double kHelixRadius_m = 0.15e-3;
constexpr double kSecondPegHeight_m = 0.6e-3;
// The instrument jaws the throws are wrapped on (see the constructor): their radius, their
// clearance from the standing part (beyond the contact cutoff, so a straight thread slides
// between them untouched), and how far they reach beyond the helix at either end.
constexpr double kJawRadius_m = 40e-6;
constexpr double kJawClearance_m = 15e-6;
constexpr double kJawOverhang_m = 0.2e-3;
// Pegs and jaws shrink to nothing over this time at the end of a throw (the instrument opens).
constexpr double kReleaseTime_s = 0.1;
// Standing hand: speed per newton of tension error, and its speed limit.
constexpr double kTensionGain_m_per_s_N = 3.0;
constexpr double kMaxHandSpeed_m_per_s = 0.02;

void CheckFixed(std::size_t count, const char* owner) {
  if (count > static_cast<std::size_t>(kMaxKnotFixedColliders)) {
    throw std::invalid_argument(std::string(owner) + ".fixed_colliders: expected at most " +
                                std::to_string(kMaxKnotFixedColliders) + ", got " +
                                std::to_string(count));
  }
}

}  // namespace

void KnotThrowOptions::Validate() const {
  auto require = [](bool ok, const char* field, const char* expected) {
    if (!ok) {
      throw std::invalid_argument(std::string("KnotThrowOptions.") + field + ": expected " +
                                  expected);
    }
  };
  require(passes >= 1 && passes <= kMaxKnotThrowPasses, "passes", "1, 2 or 3");
  require(std::isfinite(knot_x_m), "knot_x_m", "a finite position in m");
  require(speed_m_per_s > 0.0 && speed_m_per_s <= 0.1, "speed_m_per_s", "a speed in (0, 0.1] m/s");
  require(pull_speed_m_per_s > 0.0 && pull_speed_m_per_s <= 0.1, "pull_speed_m_per_s",
          "a speed in (0, 0.1] m/s");
  require(hold_tension_N > 0.0 && hold_tension_N < 1.0, "hold_tension_N", "a tension in (0, 1) N");
  require(pull_tension_N > 0.0 && pull_tension_N < 1.0, "pull_tension_N", "a tension in (0, 1) N");
  require(max_pull_m > 0.0 && max_pull_m < 1.0, "max_pull_m", "a distance in (0, 1) m");
  CheckFixed(fixed_colliders.size(), "KnotThrowOptions");
}

void KnotThrowScript::Add(const Eigen::Vector3d& p_W, Phase phase) {
  MICRODEX_CHECK(num_path_ < kMaxKnotThrowWaypoints);
  path_[num_path_++] = {p_W, phase};
}

KnotThrowScript::KnotThrowScript(const ThreadModel& model, const ThreadState& state,
                                 KnotTyingHands hands, const KnotThrowOptions& options,
                                 std::span<const Collider> more_fixed)
    : hands_(hands),
      speed_m_per_s_(options.speed_m_per_s),
      pull_speed_m_per_s_(options.pull_speed_m_per_s),
      hold_tension_N_(options.hold_tension_N),
      pull_tension_N_(options.pull_tension_N),
      max_pull_m_(options.max_pull_m),
      force_limited_pull_(options.force_limited_pull),
      phase_(Phase::kLoop) {
  options.Validate();
  CheckFixed(options.fixed_colliders.size() + more_fixed.size(), "KnotThrowOptions");
  MICRODEX_CHECK(hands.standing_slot >= 0 && hands.driver_slot >= 0);
  const int driver_node = state.grasps[hands.driver_slot].node;
  MICRODEX_CHECK(driver_node >= 0 && state.grasps[hands.standing_slot].node >= 0);
  plan_standing_W_ = state.grasps[hands.standing_slot].p_WT;
  plan_driver_W_ = state.grasps[hands.driver_slot].p_WT;
  const double x0 = options.knot_x_m;
  const double a = kJigHalf_m;
  // The standing part's line at the jig: mean y, z of the nodes under it (it lies along x).
  double y_s = 0.0, z_s = 0.0;
  int count = 0;
  for (int i = 0; i < model.num_nodes; ++i) {
    const Eigen::Vector3d p = state.x_W.col(i);
    if (std::abs(p.x() - x0) <= 1.5 * a) {
      y_s += p.y();
      z_s += p.z();
      ++count;
    }
  }
  if (count > 0) {
    y_s /= count;
    z_s /= count;
  }
  // Peg 1 just above the standing part (the thread presses on its underside as soon as the
  // driver lifts the working end); peg 2 higher, so the loop between them is open.
  const double y_p1 = y_s + model.radius_m + kPegRadius_m + 0.5 * model.def.diameter_m;
  const double y_p2 = y_s + kSecondPegHeight_m;
  // The standard jig has the driver's end to the right (+x) of the knot; with the driver on
  // the left the whole jig is turned by pi about the y axis (x -> -x, z -> -z around the
  // standing line), a rotation, so the knot keeps its handedness.
  sx_ = plan_driver_W_.x() >= x0 ? 1.0 : -1.0;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(x0 + sx_ * a, y_p1, z_s), Eigen::Vector3d(x0 - sx_ * a, y_p2, z_s)}) {
    colliders_[num_colliders_++] =
        Collider::Capsule(c - kPegHalfHeight_m * Eigen::Vector3d::UnitZ(),
                          c + kPegHalfHeight_m * Eigen::Vector3d::UnitZ(), kPegRadius_m);
  }
  auto at = [&](double dx, double y, double dz) {
    return Eigen::Vector3d(x0 + sx_ * dx, y, z_s + sx_ * dz);
  };
  // The instrument's jaws: two rigid rods along the standing part, one on either side of it out
  // of the loop's plane (the standing part lies between the open jaws), over the helix's
  // length. The helix wraps the jaws and the standing part together, as an instrument tie
  // wraps the thread on the needle holder: the wraps cannot drag the standing part (held only
  // by thread tension) out of the helix, and the loop cannot slide sideways along the pegs.
  // When the jaws are withdrawn the wraps close on the standing part.
  const double dx_h0 = -a + kPegRadius_m + 0.2e-3;
  const double dx_h1 = 0.3 * a;
  const double jaw_offset = kJawRadius_m + model.radius_m + kJawClearance_m;
  for (const double side : {-1.0, 1.0}) {
    colliders_[num_colliders_++] =
        Collider::Capsule(at(dx_h0 - kJawOverhang_m, y_s, side * jaw_offset),
                          at(dx_h1 + kJawOverhang_m, y_s, side * jaw_offset), kJawRadius_m);
  }
  Add(state.x_W.col(driver_node), Phase::kLoop);
  // The loop: up past peg 1's outer side, over both pegs, down past peg 2's outer side.
  Add(at(a + kAround_m, y_p1 + kAround_m, 0.0), Phase::kLoop);
  Add(at(-a - kAround_m, y_p2 + kAround_m, 0.0), Phase::kLoop);
  Add(at(-a - kAround_m, y_p2 - kPegRadius_m - 0.1e-3, 0.0), Phase::kLoop);
  // The helix around the standing part, starting inside the loop (y > 0): over it (the loop's
  // crossing), then `passes` times under and over, ending on the near side (y < 0).
  const double rho = kHelixRadius_m;
  const double handed = options.right ? 1.0 : -1.0;
  const double theta0 = -std::numbers::pi;
  const double theta1 = 2.0 * std::numbers::pi * options.passes;
  const int samples = 36 * options.passes + 18;
  for (int k = 0; k <= samples; ++k) {
    const double u = static_cast<double>(k) / samples;
    const double theta = theta0 + u * (theta1 - theta0);
    Add(at(dx_h0 + u * (dx_h1 - dx_h0), y_s - rho * std::cos(theta),
           -handed * rho * std::sin(theta)),
        Phase::kHelix);
  }
  // Away from the knot, passing below peg 1.
  Add(at(a + 0.6e-3, y_s - 0.4e-3, 0.0), Phase::kExit);
  Add(at(a + 2.5e-3, y_s - 0.2e-3, 0.0), Phase::kExit);
  num_jig_ = num_colliders_;
  for (int k = 0; k < num_jig_; ++k) radii_[k] = colliders_[k].radius_m;
  for (const Collider& c : options.fixed_colliders) colliders_[num_colliders_++] = c;
  for (const Collider& c : more_fixed) colliders_[num_colliders_++] = c;
  for (int k = 1; k < num_path_; ++k) {
    path_total_m_ += (path_[k].p_W - path_[k - 1].p_W).norm();
  }
}

void KnotThrowScript::KeepTension(const ThreadState& state, double h) {
  // The standing hand keeps the thread taut: it gives thread when the pull exceeds the hold
  // tension and takes it in when the thread goes slack.
  const double tension = sx_ * state.grasps[hands_.standing_slot].f_T_W.x();
  const double v = std::clamp(kTensionGain_m_per_s_N * (tension - hold_tension_N_),
                              -kMaxHandSpeed_m_per_s, kMaxHandSpeed_m_per_s);
  plan_standing_W_ += (sx_ * v * h) * Eigen::Vector3d::UnitX();
}

void KnotThrowScript::SetFixedCollider(int k, const Collider& c) {
  MICRODEX_CHECK(k >= 0 && k < num_fixed_colliders());
  colliders_[static_cast<std::size_t>(num_jig_) + static_cast<std::size_t>(k)] = c;
}

bool KnotThrowScript::Step(const ThreadModel& model, ThreadWorkspace& ws, ThreadState& state,
                           const KnotHandOffsets& offsets, double advance_m) {
  if (phase_ == Phase::kDone) return false;
  const double h = model.def.time_step_s;
  // A throw moves the strands about each other: no contact force is carried across steps.
  state.carry_contact_forces = false;
  const Grasp& standing = state.grasps[hands_.standing_slot];
  const Grasp& driver = state.grasps[hands_.driver_slot];
  const std::span<const Collider> colliders = this->colliders();
  if (phase_ == Phase::kRelease) {
    // Pegs and jaws shrink to nothing over kReleaseTime_s (the instrument opens: the loop and
    // the wraps close on the thread gradually; dropping them at once frees the thread pressed
    // against them within one step); the driver holds still, the standing hand keeps its
    // tension.
    KeepTension(state, h);
    SetGraspTarget(state, hands_.standing_slot, plan_standing_W_ + offsets.standing_W,
                   standing.roll_rad);
    SetGraspTarget(state, hands_.driver_slot, plan_driver_W_ + offsets.driver_W, driver.roll_rad);
    released_s_ += h;
    const double scale = std::max(0.0, 1.0 - released_s_ / kReleaseTime_s);
    for (int k = 0; k < num_jig_; ++k) colliders_[k].radius_m = scale * radii_[k];
    if (released_s_ >= kReleaseTime_s) {
      for (int k = 0; k < num_jig_; ++k) colliders_[k].enabled = false;
      phase_ = Phase::kPull;
    }
    StepThread(model, colliders, ws, state);
    return true;
  }
  if (phase_ != Phase::kPull) {
    // The driver follows its path.
    double advance = std::max(0.0, advance_m);
    while (advance > 0.0 && segment_ + 1 < num_path_) {
      const Eigen::Vector3d& from = path_[segment_].p_W;
      const Eigen::Vector3d& to = path_[segment_ + 1].p_W;
      const double len = (to - from).norm();
      const double step = std::min(advance, len - segment_s_m_);
      segment_s_m_ += step;
      path_s_m_ += step;
      advance -= step;
      plan_driver_W_ = len > 0.0 ? Eigen::Vector3d(from + (segment_s_m_ / len) * (to - from)) : to;
      phase_ = path_[segment_ + 1].phase;
      if (segment_s_m_ >= len) {
        ++segment_;
        segment_s_m_ = 0.0;
      }
    }
    SetGraspTarget(state, hands_.driver_slot, plan_driver_W_ + offsets.driver_W, driver.roll_rad);
    KeepTension(state, h);
    SetGraspTarget(state, hands_.standing_slot, plan_standing_W_ + offsets.standing_W,
                   standing.roll_rad);
    if (segment_ + 1 >= num_path_) phase_ = Phase::kRelease;
    StepThread(model, colliders, ws, state);
    return true;
  }
  // Pull: both hands apart along x until each feels the pull tension.
  const double dx = pull_speed_m_per_s_ * h;
  pulled_m_ += dx;
  if (force_limited_pull_) {
    // Each hand out while its tension is below the pull's (aiming 5 % above it, so that both
    // reach it), back while above.
    auto out = [&](const Grasp& g) {
      const double v =
          std::clamp(kTensionGain_m_per_s_N * (1.05 * pull_tension_N_ - g.f_T_W.norm()),
                     -kMaxHandSpeed_m_per_s, pull_speed_m_per_s_);
      return v * h;
    };
    plan_driver_W_ += (sx_ * out(driver)) * Eigen::Vector3d::UnitX();
    plan_standing_W_ -= (sx_ * out(standing)) * Eigen::Vector3d::UnitX();
  } else {
    plan_driver_W_ += (sx_ * dx) * Eigen::Vector3d::UnitX();
    plan_standing_W_ -= (sx_ * dx) * Eigen::Vector3d::UnitX();
  }
  SetGraspTarget(state, hands_.driver_slot, plan_driver_W_ + offsets.driver_W, driver.roll_rad);
  SetGraspTarget(state, hands_.standing_slot, plan_standing_W_ + offsets.standing_W,
                 standing.roll_rad);
  StepThread(model, colliders, ws, state);
  if ((driver.f_T_W.norm() >= pull_tension_N_ && standing.f_T_W.norm() >= pull_tension_N_) ||
      pulled_m_ >= max_pull_m_) {
    phase_ = Phase::kDone;
  }
  return phase_ != Phase::kDone;
}

void KnotHoldOptions::Validate() const {
  if (!(tension_N > 0.0 && tension_N < 1.0)) {
    throw std::invalid_argument("KnotHoldOptions.tension_N: expected a tension in (0, 1) N");
  }
  if (!(duration_s >= 0.0 && duration_s < 1e3)) {
    throw std::invalid_argument("KnotHoldOptions.duration_s: expected a duration in [0, 1000) s");
  }
  if (!(pull_gain_N_per_m >= 0.0 && pull_gain_N_per_m < 1e4)) {
    throw std::invalid_argument(
        "KnotHoldOptions.pull_gain_N_per_m: expected a gain in [0, 10000) N/m");
  }
  CheckFixed(fixed_colliders.size(), "KnotHoldOptions");
}

KnotHoldScript::KnotHoldScript(const ThreadModel& model, const ThreadState& state,
                               KnotTyingHands hands, const KnotHoldOptions& options)
    : hands_(hands),
      tension_N_(options.tension_N),
      pull_gain_N_per_m_(options.pull_gain_N_per_m),
      steps_left_(static_cast<int>(std::lround(options.duration_s / model.def.time_step_s))) {
  options.Validate();
  MICRODEX_CHECK(hands.standing_slot >= 0 && hands.driver_slot >= 0);
  for (const Collider& c : options.fixed_colliders) colliders_[num_colliders_++] = c;
  plan_standing_W_ = state.grasps[hands.standing_slot].p_WT;
  plan_driver_W_ = state.grasps[hands.driver_slot].p_WT;
}

void KnotHoldScript::SetFixedCollider(int k, const Collider& c) {
  MICRODEX_CHECK(k >= 0 && k < num_colliders_);
  colliders_[static_cast<std::size_t>(k)] = c;
}

bool KnotHoldScript::Step(const ThreadModel& model, ThreadWorkspace& ws, ThreadState& state,
                          const KnotHandOffsets& offsets) {
  if (steps_left_ <= 0) return false;
  const double h = model.def.time_step_s;
  // The knot is held still: its contacts keep their forces from step to step.
  state.carry_contact_forces = true;
  for (const int slot : {hands_.standing_slot, hands_.driver_slot}) {
    const bool is_standing = slot == hands_.standing_slot;
    Eigen::Vector3d& plan = is_standing ? plan_standing_W_ : plan_driver_W_;
    const Eigen::Vector3d& other = is_standing ? plan_driver_W_ : plan_standing_W_;
    const Grasp& g = state.grasps[slot];
    const Eigen::Vector3d& offset = is_standing ? offsets.standing_W : offsets.driver_W;
    // Outward: away from the other hand, along x (the thread's direction when pulled).
    const double out = plan.x() >= other.x() ? 1.0 : -1.0;
    const double tension = -out * g.f_T_W.x();
    const double target_N =
        std::max(0.1 * tension_N_, tension_N_ + pull_gain_N_per_m_ * out * offset.x());
    const double v = std::clamp(kTensionGain_m_per_s_N * (target_N - tension),
                                -kMaxHandSpeed_m_per_s, kMaxHandSpeed_m_per_s);
    plan += (out * v * h) * Eigen::Vector3d::UnitX();
    SetGraspTarget(state, slot, plan + (is_standing ? offsets.standing_W : offsets.driver_W),
                   g.roll_rad);
  }
  StepThread(model, std::span<const Collider>(colliders_.data(), num_colliders_), ws, state);
  --steps_left_;
  return steps_left_ > 0;
}

std::vector<KnotThrowOptions> ParseKnotThrows(const std::string& spec) {
  std::vector<KnotThrowOptions> throws;
  std::stringstream in(spec);
  std::string item;
  while (std::getline(in, item, ',')) {
    const bool ok = item.size() >= 1 && item.size() <= 2 && item[0] >= '1' && item[0] <= '3' &&
                    (item.size() == 1 || item[1] == 'r' || item[1] == 'l');
    if (!ok) {
      std::string message = "knot throws '";
      message += spec;
      message += "': item '";
      message += item;
      message += "': expected passes 1-3 and r or l, e.g. 2 or 1r,1l";
      throw std::invalid_argument(message);
    }
    KnotThrowOptions t;
    t.passes = item[0] - '0';
    t.right = item.size() == 1 || item[1] == 'r';
    throws.push_back(t);
  }
  if (throws.empty() || throws.size() > 3) {
    throw std::invalid_argument("knot throws '" + spec + "': expected 1 to 3 throws");
  }
  return throws;
}

void KnotStitchDef::Validate() const {
  auto positive = [](double v, const char* field) {
    if (!(v > 0.0 && v < 1.0)) {
      throw std::invalid_argument(std::string(field) + ": expected a length in (0, 1) m");
    }
  };
  positive(depth_m, "depth_m");
  positive(guide_offset_m, "guide_offset_m");
  positive(rod_radius_m, "rod_radius_m");
  positive(guide_radius_m, "guide_radius_m");
  if (!(std::isfinite(x_m) && std::isfinite(start_x_m) &&
        start_x_m < x_m - guide_offset_m - guide_radius_m)) {
    throw std::invalid_argument("start_x_m: expected the standing end before the first guide");
  }
  if (!(depth_m > rod_radius_m + guide_radius_m && guide_offset_m > rod_radius_m)) {
    throw std::invalid_argument("depth_m: expected the bite rod below the guides and between them");
  }
}

std::vector<Collider> KnotStitchDef::Colliders(double thread_radius_m) const {
  Validate();
  const double half = 4e-3;  // the rods' half length along z
  auto rod = [&](double x, double y, double r) {
    return Collider::Capsule(Eigen::Vector3d(x, y, -half), Eigen::Vector3d(x, y, half), r);
  };
  const double y_guide = -thread_radius_m - guide_radius_m - 2e-6;
  return {rod(x_m - guide_offset_m, y_guide, guide_radius_m), rod(x_m, -depth_m, rod_radius_m),
          rod(x_m + guide_offset_m, y_guide, guide_radius_m)};
}

ThreadState KnotStitchDef::Lay(const ThreadModel& model) const {
  Validate();
  const double r = model.radius_m;
  const double y_bottom = -depth_m - rod_radius_m - r - 2e-6;
  const double side = rod_radius_m + r + 3e-6;
  const std::vector<Eigen::Vector3d> path = {
      {start_x_m, 0.0, 0.0}, {x_m - guide_offset_m, 0.0, 0.0}, {x_m - side, -depth_m, 0.0},
      {x_m, y_bottom, 0.0},  {x_m + side, -depth_m, 0.0},      {x_m + guide_offset_m, 0.0, 0.0},
      {x_m + 1.0, 0.0, 0.0}};
  Eigen::Matrix3Xd x(3, model.num_nodes);
  std::size_t segment = 0;
  Eigen::Vector3d at = path.front();
  x.col(0) = at;
  for (int i = 1; i < model.num_nodes; ++i) {
    double left = model.rest_length_m[i - 1];
    while (true) {
      const Eigen::Vector3d d = path[segment + 1] - at;
      const double len = d.norm();
      if (len >= left) {
        at += (left / len) * d;
        break;
      }
      left -= len;
      at = path[segment + 1];
      ++segment;
    }
    x.col(i) = at;
  }
  return MakeThreadState(model, x);
}

}  // namespace microdex::thread
