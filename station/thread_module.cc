#include "station/thread_module.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>
#include <utility>

#include "common/base/check.h"
#include "common/thread/grasp.h"
#include "common/thread/thread_contacts.h"
#include "common/thread/thread_step.h"

namespace microdex::station {

Eigen::Matrix3Xd CalcSlackThreadNodes(const Eigen::Vector3d& p_W_a, const Eigen::Vector3d& p_W_b,
                                      const Eigen::Vector3d& side_W, double length_m,
                                      int num_nodes) {
  MICRODEX_CHECK(num_nodes >= 2 && length_m > 0);
  Eigen::Matrix3Xd x(3, num_nodes);
  const Eigen::Vector3d chord = p_W_b - p_W_a;
  const double d = chord.norm();
  MICRODEX_CHECK(d > 0);
  const Eigen::Vector3d c = chord / d;
  // Bow direction: side_W without its part along the chord (any normal when parallel).
  Eigen::Vector3d u = side_W - side_W.dot(c) * c;
  if (u.norm() < 1e-9) u = c.unitOrthogonal();
  u.normalize();
  // Arc of length L over the chord d: half-angle θ with sin θ / θ = d / L (Newton on
  // g(θ) = sin θ − (d / L) θ from θ = π/2 ... π, where g is concave and decreasing past its
  // maximum); a taut thread (d >= L) is straight.
  const double ratio = d / length_m;
  if (ratio >= 1 - 1e-12) {
    for (int i = 0; i < num_nodes; ++i) {
      x.col(i) = p_W_a + chord * (static_cast<double>(i) / (num_nodes - 1));
    }
    return x;
  }
  double theta = std::sqrt(6 * (1 - ratio));  // small-angle start: sin θ/θ ≈ 1 − θ²/6
  theta = std::min(theta, 3.0);
  for (int it = 0; it < 60; ++it) {
    const double g = std::sin(theta) - ratio * theta;
    const double dg = std::cos(theta) - ratio;
    if (dg == 0) break;
    const double next = std::clamp(theta - g / dg, 1e-9, 3.14159);
    if (std::abs(next - theta) < 1e-15) break;
    theta = next;
  }
  const double radius_m = length_m / (2 * theta);
  // Centre below the chord's midpoint, on the side away from u.
  const Eigen::Vector3d mid = 0.5 * (p_W_a + p_W_b);
  const Eigen::Vector3d centre = mid - radius_m * std::cos(theta) * u;
  for (int i = 0; i < num_nodes; ++i) {
    const double phi = -theta + 2 * theta * static_cast<double>(i) / (num_nodes - 1);
    x.col(i) = centre + radius_m * (std::sin(phi) * c + std::cos(phi) * u);
  }
  return x;
}

double CalcAlignedRmsDistance(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& target) {
  MICRODEX_CHECK(x.cols() == target.cols() && x.cols() > 0);
  const Eigen::Vector3d cx = x.rowwise().mean();
  const Eigen::Vector3d ct = target.rowwise().mean();
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (Eigen::Index i = 0; i < x.cols(); ++i)
    H += (x.col(i) - cx) * (target.col(i) - ct).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();  // x → target
  double sq = 0;
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    sq += (R * (x.col(i) - cx) - (target.col(i) - ct)).squaredNorm();
  }
  return std::sqrt(sq / static_cast<double>(x.cols()));
}

ThreadModule::ThreadModule(const scene::SceneModel& scene, SharedStitch stitch)
    : second_hand_(scene.second_hand.has_value()),
      max_force_N_(scene.haptic.max_force_N),
      max_strain_(scene.thread->max_strain) {
  const scene::ThreadSceneDef& d = *scene.thread;
  if (d.def.num_nodes > static_cast<int>(kMaxFrameThreadNodes)) {
    throw std::runtime_error(scene.path + ": thread.params: " + d.params_path +
                             ": num_nodes: expected <= " + std::to_string(kMaxFrameThreadNodes) +
                             " (the ThreadState bound)");
  }
  model_ = thread::MakeThreadModel(d.def);
  ws_ = thread::MakeThreadWorkspace(model_);
  if (scene.knot_tying) {
    // The thread laid through the stitch; the hands hold its ends where they lie.
    tie_ = scene.knot_tying;
    initial_ = tie_->stitch.Lay(model_);
    stitch_ = tie_->stitch.Colliders(model_.radius_m);
    hold_options_.tension_N = tie_->hold_tension_N;
    hold_options_.duration_s = tie_->hold_s;
    hold_options_.pull_gain_N_per_m = tie_->hold_pull_N_per_m;
    hold_options_.fixed_colliders = stitch_;
    p_W_tool_rest_ = scene.CalcIdealToolPose(0).translation();
    p_W_second_rest_ = scene.CalcIdealSecondToolPose(0).translation();
    stitch_tissue_ = stitch ? std::move(stitch) : MakeSharedStitchOnTissue(scene);
    if (stitch_tissue_) {
      // The rod's displacement follows u <- u + g (c F(u) - u), g = h / stitch_relax_s, where
      // the thread's load F(u) = F0 - k u falls as the rod gives: the error shrinks by
      // 1 - g (1 + c k) a step, stable while g (1 + c k) < 2 (c the largest compliance). The
      // stiffest the thread holds a rod is two strands, each taut to a hand one guide offset
      // away: k = 2 E A / guide_offset. The in-plane displacement follows the same law with the
      // in-plane compliance, so c is the largest of both.
      stitch_gain_ = model_.def.time_step_s / tie_->stitch_relax_s;
      const double ea_N =
          model_.def.youngs_modulus_Pa * std::numbers::pi * model_.radius_m * model_.radius_m;
      const double k_N_per_m = 2 * ea_N / tie_->stitch.guide_offset_m;
      const double c_m_per_N = std::max(stitch_tissue_->compliance.c_m_per_N.diagonal().maxCoeff(),
                                        stitch_tissue_->HasInPlane()
                                            ? stitch_tissue_->in_plane_m_per_N.diagonal().maxCoeff()
                                            : 0.0);
      const double min_relax_s = model_.def.time_step_s * (1 + c_m_per_N * k_N_per_m) / 2;
      if (!(stitch_gain_ * (1 + c_m_per_N * k_N_per_m) < 2)) {
        throw std::runtime_error(
            scene.path + ": knot_tying.stitch_relax_s: " + std::to_string(tie_->stitch_relax_s) +
            " s is too short for this tissue: the stitch would oscillate (its compliance " +
            std::to_string(c_m_per_N) + " m/N against the thread's " + std::to_string(k_N_per_m) +
            " N/m needs more than " + std::to_string(min_relax_s) + " s)");
      }
      // Cut-through: while the bite's low-passed load L exceeds the threshold F, the cut w
      // grows by g c_b (L - F) a step, at the rate the patch's elastic displacement follows the
      // load, and never heals. The pair (L, w) then steps by [[1 - g (1 + c k), -g k],
      // [g c, 1]], stable under the same bound g (1 + c k) < 2: the cut makes the load settle
      // on F where the thread's pull relaxes as the bite rises, and cuts on while the hands keep
      // pulling harder than F.
      bite_tear_N_ = tie_->bite_tear_N;
      bite_compliance_m_per_N_ = stitch_tissue_->compliance.c_m_per_N(kBiteRod, kBiteRod);
      bite_pull_out_m_ =
          tie_->stitch.depth_m + tie_->stitch.rod_radius_m + model_.radius_m + tie_->surface_y_m;
      if (bite_tear_N_ > 0 && !(bite_pull_out_m_ > 0)) {
        throw std::runtime_error(scene.path +
                                 ": knot_tying.stitch.depth_m: the bite must lie under the "
                                 "surface (surface_y_m) for it to tear (bite_tear_N)");
      }
    }
  } else {
    initial_ = thread::MakeThreadState(
        model_, CalcSlackThreadNodes(d.p_W_anchor, scene.CalcIdealToolPose(0).translation(),
                                     d.slack_side_W, d.def.length_m, model_.num_nodes));
  }
  if (std::isfinite(d.floor_height_m)) {
    colliders_[0] =
        thread::Collider::Plane(Eigen::Vector3d(0, 0, d.floor_height_m), Eigen::Vector3d::UnitZ());
    num_colliders_ = 1;
    floor_z_m_ = d.floor_height_m;
  }
  anchor_slot_ = thread::GraspNode(model_, 0, initial_);
  tool_node_ = model_.num_nodes - 1;
  tool_slot_ = thread::GraspNode(model_, tool_node_, initial_);
  MICRODEX_CHECK(anchor_slot_ >= 0 && tool_slot_ >= 0);  // max_grasps >= 2 (scene validation)
  if (tie_) {
    for (int k = 0; k < tie_->throws; ++k) {
      state::KnotTieState probe;
      ThrowOptions(probe, k).Validate();  // the scene's values, named if bad
    }
    hold_options_.Validate();
  }
  if (scene.task.kind == scene::TaskKind::kNylonLoop) {
    thread::ThreadState t = initial_;
    const double dt_s = 1.0 / scene.haptic.rate_hz;
    const auto steps = static_cast<long>(
        std::lround(scene.task.passes * scene.task.pass_duration_s * scene.haptic.rate_hz));
    const std::span<const thread::Collider> colliders(colliders_.data(), num_colliders_);
    for (long k = 0; k < steps; ++k) {
      const Eigen::Isometry3d X_WT = scene.CalcIdealToolPose(static_cast<double>(k) * dt_s);
      thread::SetGraspTarget(t, tool_slot_, X_WT.translation(), 0.0);
      thread::StepThread(model_, colliders, ws_, t);
    }
    target_W_ = t.x_W;
  }
}

void ThreadModule::InitState(state::StationState& s) const {
  s.thread = state::ThreadModuleState{initial_};
  if (tie_) {
    s.thread->tie.hands.standing_slot = anchor_slot_;
    s.thread->tie.hands.driver_slot = tool_slot_;
  }
}

thread::KnotThrowOptions ThreadModule::ThrowOptions(const state::KnotTieState& tie, int k) const {
  thread::KnotThrowOptions o;
  o.passes = std::max<int>(tie.passes[static_cast<std::size_t>(k)], 1);
  o.right = tie.right[static_cast<std::size_t>(k)] != 0;
  o.knot_x_m = k == 0 ? tie_->first_jig_x_m : tie_->next_jig_x_m;
  o.speed_m_per_s = tie_->speed_m_per_s;
  o.hold_tension_N = tie_->throw_tension_N;
  o.pull_tension_N = tie_->pull_tension_N;
  o.force_limited_pull = tie_->force_limited_pull;
  return o;
}

std::array<thread::Collider, kStitchRods> ThreadModule::MovedStitch(
    const state::KnotTieState& tie) const {
  std::array<thread::Collider, kStitchRods> rods{};
  const Eigen::Vector3d w_m =
      stitch_tissue_ ? stitch_tissue_->Displacement_m(tie.stitch_load_N) : Eigen::Vector3d::Zero();
  for (int k = 0; k < kStitchRods; ++k) {
    thread::Collider c = stitch_[static_cast<std::size_t>(k)];
    if (stitch_tissue_) {
      const double cut_m = k == kBiteRod ? tie.bite_cut_m : 0.0;
      Eigen::Vector3d d_W = (w_m[k] + cut_m) * stitch_tissue_->n_W;
      if (stitch_tissue_->HasInPlane()) {
        d_W += stitch_tissue_->InPlaneDisplacement_W(tie.stitch_in_plane_load_N, k);
      }
      c.a_W += d_W;
      c.b_W += d_W;
    }
    rods[static_cast<std::size_t>(k)] = c;
  }
  return rods;
}

void ThreadModule::UpdateStitchLoads(int num_colliders, const thread::ThreadState& thread,
                                     state::KnotTieState& tie) const {
  if (!stitch_tissue_) return;
  // Each rod's load from the thread's pull where it leaves the rod, cut 0.5 mm away.
  const int margin_links = std::max(
      1, static_cast<int>(std::lround(0.5e-3 * (model_.num_nodes - 1) / model_.def.length_m)));
  for (int k = 0; k < kStitchRods; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const Eigen::Vector3d f_W = thread::CalcColliderLoad(
        model_, ws_, thread, num_colliders - kStitchRods + k, margin_links);
    double f_N = f_W.dot(stitch_tissue_->n_W);
    if (!std::isfinite(f_N)) f_N = 0;
    tie.stitch_force_N[i] = f_N;
    tie.stitch_load_N[i] += stitch_gain_ * (f_N - tie.stitch_load_N[i]);
    if (stitch_tissue_->HasInPlane()) {
      Eigen::Vector2d f_S = stitch_tissue_->t_W.transpose() * f_W;
      if (!f_S.allFinite()) f_S.setZero();
      for (int d = 0; d < 2; ++d) {
        double& load_N = tie.stitch_in_plane_load_N[2 * i + static_cast<std::size_t>(d)];
        load_N += stitch_gain_ * (f_S[d] - load_N);
      }
    }
  }
  // The bite cuts up through the tissue while its load exceeds the tear threshold (the
  // constructor's comment); pulled out once the thread under it has reached the surface.
  const double excess_N = tie.stitch_load_N[kBiteRod] - bite_tear_N_;
  if (bite_tear_N_ > 0 && tie.bite_pulled_out == 0 && excess_N > 0) {
    tie.bite_cut_m = std::min(bite_pull_out_m_,
                              tie.bite_cut_m + stitch_gain_ * bite_compliance_m_per_N_ * excess_N);
    if (tie.bite_cut_m >= bite_pull_out_m_) tie.bite_pulled_out = 1;
  }
}

void ThreadModule::StepKnotTying(const ToolInput& in, state::StationState& s) {
  state::ThreadModuleState& t = *s.thread;
  state::KnotTieState& k = t.tie;
  thread::ThreadState& th = t.thread;
  const double h = model_.def.time_step_s;
  // A button pressed chooses the next throw: 1 single right, 2 single left, 3 double right,
  // 4 double left (other values are ignored).
  const std::uint32_t buttons = s.tool.buttons;
  const bool pressed = buttons != 0 && k.prev_buttons == 0;
  k.prev_buttons = buttons;
  if (pressed && buttons <= 4 && k.chosen < tie_->throws && k.chosen < 3) {
    k.passes[static_cast<std::size_t>(k.chosen)] = static_cast<std::int8_t>(buttons <= 2 ? 1 : 2);
    k.right[static_cast<std::size_t>(k.chosen)] = static_cast<std::int8_t>(buttons % 2);
    ++k.chosen;
  }
  // The hands' deviations from their rest poses, weighted by the coupling: full in the hold
  // after the last throw, none while the throws are tied and pulled (a deviation there undoes
  // throws: tremor and drift of 20-200 um at the ends loosen a throw as it is pulled, and the
  // next throw's jig then misses it; see assets/scenes/README.md).
  const bool guided = !k.holding;
  constexpr double kCouplingRate_per_s = 4.0;
  k.coupling = std::clamp(k.coupling + (guided ? -1.0 : 1.0) * kCouplingRate_per_s * h, 0.0, 1.0);
  Eigen::Vector3d d_tool = in.X_WT.translation() - p_W_tool_rest_;
  Eigen::Vector3d d_second =
      in.second_tool != nullptr
          ? Eigen::Vector3d(in.second_tool->X_WT.translation() - p_W_second_rest_)
          : Eigen::Vector3d::Zero();
  if (!d_tool.allFinite()) d_tool.setZero();
  if (!d_second.allFinite()) d_second.setZero();
  d_tool *= k.coupling;
  d_second *= k.coupling;
  // The knot is tied once all its throws are chosen, each throw as soon as the last one is
  // pulled (a pause between throws lets the pulled throw settle off the next jig's path and
  // the next throw can miss it). The hands' plans are their targets less the deviations
  // applied.
  if (k.script.done() && !k.holding && k.started < tie_->throws && k.chosen >= tie_->throws) {
    thread::SetGraspTarget(th, tool_slot_, th.grasps[tool_slot_].p_WT - k.applied_tool_W,
                           th.grasps[tool_slot_].roll_rad);
    thread::SetGraspTarget(th, anchor_slot_, th.grasps[anchor_slot_].p_WT - k.applied_second_W,
                           th.grasps[anchor_slot_].roll_rad);
    thread::KnotThrowOptions o = ThrowOptions(k, k.started);
    k.script = thread::KnotThrowScript(model_, th, k.hands, o, MovedStitch(k));
    ++k.started;
    k.applied_tool_W.setZero();
    k.applied_second_W.setZero();
  }
  auto offsets = [&] {
    thread::KnotHandOffsets o;
    o.driver_W = k.hands.driver_slot == tool_slot_ ? d_tool : d_second;
    o.standing_W = k.hands.driver_slot == tool_slot_ ? d_second : d_tool;
    return o;
  };
  const Eigen::Vector3d applied_tool_before = k.applied_tool_W;
  const Eigen::Vector3d applied_second_before = k.applied_second_W;
  k.applied_tool_W = d_tool;
  k.applied_second_W = d_second;
  const std::array<thread::Collider, kStitchRods> rods = MovedStitch(k);
  if (!k.script.done()) {
    for (int r = 0; r < kStitchRods; ++r) {
      k.script.SetFixedCollider(k.script.num_fixed_colliders() - kStitchRods + r,
                                rods[static_cast<std::size_t>(r)]);
    }
    const bool more = k.script.Step(model_, ws_, th, offsets(), tie_->speed_m_per_s * h);
    UpdateStitchLoads(static_cast<int>(k.script.colliders().size()), th, k);
    if (!more) {
      // Pulled: the next throw is tied with the other end.
      ++k.pulled;
      std::swap(k.hands.standing_slot, k.hands.driver_slot);
      if (k.pulled >= tie_->throws) {
        for (const auto& [slot, applied] :
             {std::pair{tool_slot_, d_tool}, std::pair{anchor_slot_, d_second}}) {
          thread::SetGraspTarget(th, slot, th.grasps[slot].p_WT - applied,
                                 th.grasps[slot].roll_rad);
        }
        k.hold = thread::KnotHoldScript(model_, th, k.hands, hold_options_);
        for (int r = 0; r < kStitchRods; ++r) {
          k.hold.SetFixedCollider(r, rods[static_cast<std::size_t>(r)]);
        }
        k.holding = 1;
      }
    }
    return;
  }
  if (k.holding && !k.done) {
    for (int r = 0; r < kStitchRods; ++r)
      k.hold.SetFixedCollider(r, rods[static_cast<std::size_t>(r)]);
    if (!k.hold.Step(model_, ws_, th, offsets())) k.done = 1;
    UpdateStitchLoads(static_cast<int>(k.hold.colliders().size()), th, k);
    return;
  }
  // Before the first throw is chosen the suture lies as laid through the stitch (the tie's
  // script starts from that state).
  if (k.started == 0) {
    k.applied_tool_W.setZero();
    k.applied_second_W.setZero();
    k.coupling = 0;
    return;
  }
  // Waiting (for a choice, or done): both ends follow the hands about where they were left.
  for (const auto& [slot, before, now] :
       {std::tuple{tool_slot_, applied_tool_before, d_tool},
        std::tuple{anchor_slot_, applied_second_before, d_second}}) {
    thread::SetGraspTarget(th, slot, th.grasps[slot].p_WT - before + now, th.grasps[slot].roll_rad);
  }
  thread::StepThread(model_, rods, ws_, th);
  UpdateStitchLoads(kStitchRods, th, k);
}

void ThreadModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& f_T_W) {
  state::ThreadModuleState& t = *s.thread;
  if (tie_) {
    StepKnotTying(in, s);
    t.f_T_W = thread::GraspForce(t.thread, tool_slot_, max_force_N_);
    f_T_W += t.f_T_W;
    t.f_T2_W = thread::GraspForce(t.thread, anchor_slot_, max_force_N_);
    return;
  }
  // The grasped node follows the tool tip; its torsion follows the tool's roll about x.
  const Eigen::Matrix3d& R = in.X_WT.linear();
  const double roll_rad = std::atan2(R(2, 1), R(2, 2));
  // The tool's tip rests on the table: it does not drag the node it holds through the floor
  // (the floor's contact would then hold the node against the grasp at the force limit).
  Eigen::Vector3d p_WT = in.X_WT.translation();
  if (num_colliders_ > 0) p_WT.z() = std::max(p_WT.z(), floor_z_m_ + model_.radius_m);
  thread::SetGraspTarget(t.thread, tool_slot_, p_WT, roll_rad);
  if (second_hand_ && in.second_tool != nullptr) {
    const Eigen::Isometry3d& X_WT2 = in.second_tool->X_WT;
    const Eigen::Matrix3d& R2 = X_WT2.linear();
    Eigen::Vector3d p_WT2 = X_WT2.translation();
    if (num_colliders_ > 0) p_WT2.z() = std::max(p_WT2.z(), floor_z_m_ + model_.radius_m);
    thread::SetGraspTarget(t.thread, anchor_slot_, p_WT2, std::atan2(R2(2, 1), R2(2, 2)));
  }
  thread::StepThread(model_, std::span<const thread::Collider>(colliders_.data(), num_colliders_),
                     ws_, t.thread);
  t.f_T_W = thread::GraspForce(t.thread, tool_slot_, max_force_N_);
  f_T_W += t.f_T_W;
  if (second_hand_) t.f_T2_W = thread::GraspForce(t.thread, anchor_slot_, max_force_N_);
  if (target_W_.cols() > 0) t.shape_error_m = CalcAlignedRmsDistance(t.thread.x_W, target_W_);
}

ModuleStatus ThreadModule::Status(const state::StationState& s) const {
  const thread::ThreadStatus& st = s.thread->thread.status;
  ModuleStatus out;
  out.fault = st.max_strain > max_strain_;
  out.fault_value = st.max_strain;
  out.error_estimate = st.max_strain;
  out.warnings = static_cast<std::uint32_t>(st.nonfinite_resets + st.factorization_failures +
                                            st.contact_overflows);
  return out;
}

Eigen::Vector3d ThreadModule::SecondToolForce(const state::StationState& s) const {
  return s.thread->f_T2_W;
}

void ThreadModule::WriteFrame(const state::StationState& s, std::uint64_t step,
                              std::int64_t stamp_ns, LargeFrames& frames) {
  const state::ThreadModuleState& t = *s.thread;
  ThreadFrame& f = frames.thread.back();
  f.step = step;
  f.stamp_ns = stamp_ns;
  f.num_nodes = model_.num_nodes;
  for (int i = 0; i < model_.num_nodes; ++i) {
    f.p_W[i] = {t.thread.x_W(0, i), t.thread.x_W(1, i), t.thread.x_W(2, i)};
  }
  f.max_strain = t.thread.status.max_strain;
  f.grasped_node = tool_node_;
  f.f_T_W = {t.f_T_W.x(), t.f_T_W.y(), t.f_T_W.z()};
  frames.thread.Publish();
}

}  // namespace microdex::station
