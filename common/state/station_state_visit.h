#pragma once
// The one list of StationState's fields, in their fixed order. The hash (state_hash.h), the
// equality and the tests walk it; a field added to the state and not listed here is caught by
// the test that changes every listed field and compares copies
// (tests/unit/state/station_state_test.cc).
//
// VisitStationState(state, v) calls v(name, p, n) for each field, where p points to n
// consecutive scalars (double, float, integers, bool; enums as their underlying integer).
// State is `StationState` or `const StationState`. Counted arrays are visited up to their
// count only (the slots beyond it are unused capacity, not state); an optional section is
// preceded by its presence flag.

#include <algorithm>
#include <cstddef>
#include <type_traits>

#include "common/state/station_state.h"

namespace microdex::state {
namespace visit_internal {

template <typename T, typename Same>
using Like = std::conditional_t<std::is_const_v<Same>, const T, T>;

// An enum as its underlying integer.
template <typename E, typename V>
void Enum(const char* name, E& e, V& v) {
  using U = std::underlying_type_t<std::remove_const_t<E>>;
  v(name, reinterpret_cast<Like<U, E>*>(&e), 1);
}

template <typename M, typename V>
void Matrix(const char* name, M& m, V& v) {
  v(name, m.data(), static_cast<std::size_t>(m.size()));
}

template <typename X, typename V>
void Pose(const char* name, X& X_AB, V& v) {
  v(name, X_AB.matrix().data(), 16);
}

// The first `count` elements of a vector or array, each through f(element); count clamped
// to the container's size.
template <typename C, typename F>
void Counted(C& c, int count, F f) {
  const std::size_t n = std::min(static_cast<std::size_t>(std::max(count, 0)), c.size());
  for (std::size_t i = 0; i < n; ++i) f(c[i]);
}

// A tool's fields under the names of the first tool ("tool.…") or of the second ("second_tool.…").
inline constexpr const char* kToolNames[2][8] = {
    {"tool.X_WT_device", "tool.gripper", "tool.buttons", "tool.X_WT", "tool.f_T_W", "tool.tau_T_W",
     "tool.force_warnings", "tool.device_fault"},
    {"second_tool.X_WT_device", "second_tool.gripper", "second_tool.buttons", "second_tool.X_WT",
     "second_tool.f_T_W", "second_tool.tau_T_W", "second_tool.force_warnings",
     "second_tool.device_fault"}};

template <typename S, typename V>
void Tool(S& t, V& v, int hand = 0) {
  const char* const* n = kToolNames[hand];
  Pose(n[0], t.X_WT_device, v);
  v(n[1], &t.gripper, 1);
  v(n[2], &t.buttons, 1);
  Pose(n[3], t.X_WT, v);
  Matrix(n[4], t.f_T_W, v);
  Matrix(n[5], t.tau_T_W, v);
  v(n[6], &t.force_warnings, 1);
  v(n[7], &t.device_fault, 1);
}

template <typename S, typename V>
void Cues(S& c, V& v) {
  v("cues.active", &c.active, 1);
  v("cues.param", c.param.data(), c.param.size());
  Matrix("cues.tremor_filter.hp_z1", c.tremor_filter.hp_z1, v);
  Matrix("cues.tremor_filter.hp_z2", c.tremor_filter.hp_z2, v);
  Matrix("cues.tremor_filter.lp_z1", c.tremor_filter.lp_z1, v);
  Matrix("cues.tremor_filter.lp_z2", c.tremor_filter.lp_z2, v);
  v("cues.tremor_filter.started", &c.tremor_filter.started, 1);
  Matrix("cues.tremor_band_m", c.tremor_band_m, v);
  v("cues.clearance_m", &c.clearance_m, 1);
  v("cues.deviation_m", &c.deviation_m, 1);
  Matrix("cues.p_W_nearest", c.p_W_nearest, v);
  v("cues.click", &c.click, 1);
  v("cues.error", &c.error, 1);
  auto& pr = c.prediction.predictor;
  Matrix("cues.prediction.predictor.lp_z1", pr.lp_z1, v);
  Matrix("cues.prediction.predictor.lp_z2", pr.lp_z2, v);
  Matrix("cues.prediction.predictor.p_prev", pr.p_prev, v);
  Matrix("cues.prediction.predictor.v_prev", pr.v_prev, v);
  Matrix("cues.prediction.predictor.p_start", pr.p_start, v);
  v("cues.prediction.predictor.started", &pr.started, 1);
  v("cues.prediction.predictor.moving", &pr.moving, 1);
  v("cues.prediction.predictor.t_s", &pr.t_s, 1);
  v("cues.prediction.predictor.still_s", &pr.still_s, 1);
  v("cues.prediction.predictor.over_s", &pr.over_s, 1);
  v("cues.prediction.predictor.warning", &pr.warning, 1);
  Matrix("cues.prediction.p_W_end", c.prediction.p_W_end, v);
  v("cues.prediction.error_m", &c.prediction.error_m, 1);
  v("cues.prediction.valid", &c.prediction.valid, 1);
  v("cues.force_rate_limited", &c.force_rate_limited, 1);
  Matrix("cues.f_cue_W", c.f_cue_W, v);
  v("cues.pending_count", &c.pending_count, 1);
  Counted(c.pending, c.pending_count, [&](auto& r) {
    v("cues.pending[].cue_id", &r.cue_id, 1);
    Enum("cues.pending[].kind", r.kind, v);
    v("cues.pending[].param", &r.param, 1);
    v("cues.pending[].apply_at_step", &r.apply_at_step, 1);
    v("cues.pending[].off", &r.off, 1);
  });
  v("cues.ack_count", &c.ack_count, 1);
  Counted(c.acks, c.ack_count, [&](auto& a) {
    v("cues.acks[].cue_id", &a.cue_id, 1);
    Enum("cues.acks[].kind", a.kind, v);
    v("cues.acks[].param", &a.param, 1);
    v("cues.acks[].off", &a.off, 1);
  });
}

template <typename S, typename V>
void Score(S& s, V& v) {
  v("score.time_s", &s.time_s, 1);
  v("score.time_in_contact_s", &s.time_in_contact_s, 1);
  v("score.contacts", &s.contacts, 1);
  v("score.clearance_sum_m", &s.clearance_sum_m, 1);
  v("score.clearance_samples", &s.clearance_samples, 1);
  v("score.min_clearance_m", &s.min_clearance_m, 1);
  v("score.path_length_m", &s.path_length_m, 1);
  v("score.ideal_path_length_m", &s.ideal_path_length_m, 1);
  v("score.tremor_sq_sum_m2", &s.tremor_sq_sum_m2, 1);
  v("score.tremor_samples", &s.tremor_samples, 1);
  v("score.in_episode", &s.in_episode, 1);
  v("score.steps_free", &s.steps_free, 1);
  v("score.have_prev", &s.have_prev, 1);
  v("score.p_WT_device_prev", s.p_WT_device_prev.data(), 3);
  v("score.p_WT_ideal_prev", s.p_WT_ideal_prev.data(), 3);
  v("score.deviation_sum_m", &s.deviation_sum_m, 1);
  v("score.deviation_max_m", &s.deviation_max_m, 1);
  v("score.drift_sum_m", &s.drift_sum_m, 1);
  v("score.deviation_samples", &s.deviation_samples, 1);
  v("score.time_outside_s", &s.time_outside_s, 1);
  v("score.progress", &s.progress, 1);
  v("score.passes_done", &s.passes_done, 1);
  v("score.outcome", &s.outcome, 1);
  v("score.end_step", &s.end_step, 1);
  v("score.goal_time_s", &s.goal_time_s, 1);
  v("score.object_rotation_rad", &s.object_rotation_rad, 1);
  v("score.jaw_alignment_rad", &s.jaw_alignment_rad, 1);
  v("score.object_drops", &s.object_drops, 1);
  v("score.answers", &s.answers, 1);
  v("score.wrong_answers", &s.wrong_answers, 1);
  v("score.response_time_sum_s", &s.response_time_sum_s, 1);
  v("score.stitches", &s.stitches, 1);
  v("score.spacing_error_rad", &s.spacing_error_rad, 1);
  v("score.bite_error_m", &s.bite_error_m, 1);
  v("score.shape_error_m", &s.shape_error_m, 1);
  v("score.throws_pulled", &s.throws_pulled, 1);
  v("score.tied_knot", &s.tied_knot, 1);
  v("score.bite_pulled_out", &s.bite_pulled_out, 1);
  v("score.tension_sq_sum", &s.tension_sq_sum, 1);
  v("score.tension_samples", &s.tension_samples, 1);
  v("score.entry_error_m", &s.entry_error_m, 1);
  v("score.exit_error_m", &s.exit_error_m, 1);
  v("score.peak_strain", &s.peak_strain, 1);
  v("score.torn_m", &s.torn_m, 1);
  v("score.off_circle_m", &s.off_circle_m, 1);
  v("score.punctures", &s.punctures, 1);
  v("score.fault", &s.fault, 1);
  v("score.fault_value", &s.fault_value, 1);
  v("score.contact_event", &s.contact_event, 1);
}

template <typename S, typename V>
void Needle(S& n, V& v) {
  Pose("needle.X_WN", n.X_WN, v);
  Enum("needle.clearance.status", n.clearance.status, v);
  v("needle.clearance.clearance_m", &n.clearance.clearance_m, 1);
  v("needle.clearance.contact", &n.clearance.contact, 1);
  v("needle.clearance.s_rad", &n.clearance.s_rad, 1);
  Matrix("needle.clearance.p_WD", n.clearance.p_WD, v);
  Matrix("needle.clearance.p_WB", n.clearance.p_WB, v);
  v("needle.error_estimate_m", &n.error_estimate_m, 1);
  v("needle.warnings", &n.warnings, 1);
}

template <typename S, typename V>
void Tremor(S& t, V& v) {
  v("tremor.band_m", &t.band_m, 1);
  v("tremor.mean_square_m2", &t.mean_square_m2, 1);
}

template <typename S, typename V>
void Thread(S& m, V& v) {
  auto& t = m.thread;
  v("thread.time_s", &t.time_s, 1);
  Matrix("thread.x_W", t.x_W, v);
  Matrix("thread.v_W", t.v_W, v);
  Matrix("thread.q_rad", t.q_rad, v);
  Matrix("thread.qdot_rad_per_s", t.qdot_rad_per_s, v);
  int num_grasps = static_cast<int>(t.grasps.size());
  v("thread.grasps.size", &num_grasps, 1);
  Counted(t.grasps, num_grasps, [&](auto& g) {
    v("thread.grasps[].node", &g.node, 1);
    Matrix("thread.grasps[].p_WT", g.p_WT, v);
    v("thread.grasps[].roll_rad", &g.roll_rad, 1);
    Matrix("thread.grasps[].f_T_W", g.f_T_W, v);
  });
  v("thread.carry_contact_forces", &t.carry_contact_forces, 1);
  v("thread.num_carried", &t.num_carried, 1);
  Counted(t.carried, t.num_carried, [&](auto& c) {
    v("thread.carried[].link_a", &c.link_a, 1);
    v("thread.carried[].link_b", &c.link_b, 1);
    Matrix("thread.carried[].n_W", c.n_W, v);
    v("thread.carried[].force_N", &c.force_N, 1);
  });
  auto& s = t.status;
  v("thread.status.steps", &s.steps, 1);
  v("thread.status.nonfinite_resets", &s.nonfinite_resets, 1);
  v("thread.status.factorization_failures", &s.factorization_failures, 1);
  v("thread.status.contact_overflows", &s.contact_overflows, 1);
  v("thread.status.guard_corrections", &s.guard_corrections, 1);
  v("thread.status.strain_corrections", &s.strain_corrections, 1);
  v("thread.status.num_candidate_pairs", &s.num_candidate_pairs, 1);
  v("thread.status.num_self_contacts", &s.num_self_contacts, 1);
  v("thread.status.num_object_contacts", &s.num_object_contacts, 1);
  v("thread.status.num_exact_pairs", &s.num_exact_pairs, 1);
  v("thread.status.num_bound_pairs", &s.num_bound_pairs, 1);
  v("thread.status.num_friction_contacts", &s.num_friction_contacts, 1);
  v("thread.status.num_sliding_contacts", &s.num_sliding_contacts, 1);
  v("thread.status.max_strain", &s.max_strain, 1);
  Matrix("thread.f_T_W", m.f_T_W, v);
  Matrix("thread.f_T2_W", m.f_T2_W, v);
  v("thread.shape_error_m", &m.shape_error_m, 1);
  auto& k = m.tie;
  auto prefixed = [&](const char* prefix) {
    return [&v, prefix](const char* name, auto* p, std::size_t n) {
      (void)name;
      v(prefix, p, n);
    };
  };
  auto script = prefixed("thread.tie.script");
  std::remove_cvref_t<decltype(k.script)>::VisitFields(k.script, script);
  auto hold = prefixed("thread.tie.hold");
  std::remove_cvref_t<decltype(k.hold)>::VisitFields(k.hold, hold);
  v("thread.tie.hands", &k.hands.standing_slot, 1);
  v("thread.tie.hands", &k.hands.driver_slot, 1);
  v("thread.tie.chosen", &k.chosen, 1);
  v("thread.tie.started", &k.started, 1);
  v("thread.tie.pulled", &k.pulled, 1);
  v("thread.tie.passes", k.passes.data(), k.passes.size());
  v("thread.tie.right", k.right.data(), k.right.size());
  v("thread.tie.prev_buttons", &k.prev_buttons, 1);
  v("thread.tie.holding", &k.holding, 1);
  v("thread.tie.done", &k.done, 1);
  v("thread.tie.coupling", &k.coupling, 1);
  Matrix("thread.tie.applied_tool_W", k.applied_tool_W, v);
  Matrix("thread.tie.applied_second_W", k.applied_second_W, v);
  v("thread.tie.stitch_force_N", k.stitch_force_N.data(), k.stitch_force_N.size());
  v("thread.tie.stitch_load_N", k.stitch_load_N.data(), k.stitch_load_N.size());
  v("thread.tie.stitch_in_plane_load_N", k.stitch_in_plane_load_N.data(),
    k.stitch_in_plane_load_N.size());
  v("thread.tie.bite_cut_m", &k.bite_cut_m, 1);
  v("thread.tie.bite_pulled_out", &k.bite_pulled_out, 1);
}

template <typename S, typename V>
void Tissue(S& m, V& v) {
  auto& t = m.tissue;
  // The field on the last good mesh (the only part of the grid the next step reads).
  v("tissue.num_field_nodes", &t.num_field_nodes, 1);
  const std::size_t nf = std::min(static_cast<std::size_t>(std::max(t.num_field_nodes, 0)),
                                  std::min(t.field_nodes.size(), t.field_w_m.size()));
  v("tissue.field_nodes", t.field_nodes.data(), nf);
  v("tissue.field_w_m", t.field_w_m.data(), nf);
  v("tissue.step", &t.step, 1);
  v("tissue.num_leaves", &t.num_leaves, 1);
  Counted(t.leaves, t.num_leaves, [&](auto& l) {
    v("tissue.leaves[].ci", &l.ci, 1);
    v("tissue.leaves[].cj", &l.cj, 1);
    v("tissue.leaves[].level", &l.level, 1);
    v("tissue.leaves[].hanging_mask", &l.hanging_mask, 1);
  });
  v("tissue.num_contacts", &t.num_contacts, 1);
  const std::size_t nc = std::min(static_cast<std::size_t>(std::max(t.num_contacts, 0)),
                                  std::min(t.contact_nodes.size(), t.contact_force_N.size()));
  v("tissue.contact_nodes", t.contact_nodes.data(), nc);
  v("tissue.contact_force_N", t.contact_force_N.data(), nc);
  Matrix("tissue.f_T_S", t.f_T_S, v);
  Matrix("tissue.tau_T_S", t.tau_T_S, v);
  Enum("tissue.status", t.status, v);
  v("tissue.num_failed_steps", &t.num_failed_steps, 1);
  v("tissue.field_tool_pose.x_m", &t.field_tool_pose.x_m, 1);
  v("tissue.field_tool_pose.y_m", &t.field_tool_pose.y_m, 1);
  v("tissue.field_tool_pose.angle_rad", &t.field_tool_pose.angle_rad, 1);
  v("tissue.field_tool_pose_valid", &t.field_tool_pose_valid, 1);
  v("tissue.mesh_anchor.valid", &t.mesh_anchor.valid, 1);
  v("tissue.mesh_anchor.cx_m", &t.mesh_anchor.cx_m, 1);
  v("tissue.mesh_anchor.cy_m", &t.mesh_anchor.cy_m, 1);
  v("tissue.mesh_anchor.x_lo_m", &t.mesh_anchor.x_lo_m, 1);
  v("tissue.mesh_anchor.x_hi_m", &t.mesh_anchor.x_hi_m, 1);
  v("tissue.mesh_anchor.y_lo_m", &t.mesh_anchor.y_lo_m, 1);
  v("tissue.mesh_anchor.y_hi_m", &t.mesh_anchor.y_hi_m, 1);
  v("tissue.mesh_anchor.slide_x", &t.mesh_anchor.slide_x, 1);
  v("tissue.mesh_anchor.slide_y", &t.mesh_anchor.slide_y, 1);
  v("tissue.mesh_anchor.twist_r1_m", &t.mesh_anchor.twist_r1_m, 1);
  v("tissue.mesh_anchor.twist_r2_m", &t.mesh_anchor.twist_r2_m, 1);
  v("tissue.mesh_anchor.num_points", &t.mesh_anchor.num_points, 1);
  v("tissue.mesh_anchor.x_m", t.mesh_anchor.x_m.data(), t.mesh_anchor.x_m.size());
  v("tissue.mesh_anchor.y_m", t.mesh_anchor.y_m.data(), t.mesh_anchor.y_m.size());
  v("tissue.field_map.x.lo_m", &t.field_map.x.lo_m, 1);
  v("tissue.field_map.x.hi_m", &t.field_map.x.hi_m, 1);
  v("tissue.field_map.x.length_m", &t.field_map.x.length_m, 1);
  v("tissue.field_map.x.shift_m", &t.field_map.x.shift_m, 1);
  v("tissue.field_map.y.lo_m", &t.field_map.y.lo_m, 1);
  v("tissue.field_map.y.hi_m", &t.field_map.y.hi_m, 1);
  v("tissue.field_map.y.length_m", &t.field_map.y.length_m, 1);
  v("tissue.field_map.y.shift_m", &t.field_map.y.shift_m, 1);
  v("tissue.field_map.twist.cx_m", &t.field_map.twist.cx_m, 1);
  v("tissue.field_map.twist.cy_m", &t.field_map.twist.cy_m, 1);
  v("tissue.field_map.twist.r1_m", &t.field_map.twist.r1_m, 1);
  v("tissue.field_map.twist.r2_m", &t.field_map.twist.r2_m, 1);
  v("tissue.field_map.twist.turn_rad", &t.field_map.twist.turn_rad, 1);
  Matrix("tissue.blend_f_N", t.blend_f_N, v);
  Matrix("tissue.blend_tau_Nm", t.blend_tau_Nm, v);
  Matrix("tissue.f_change_N", t.f_change_N, v);
  Matrix("tissue.tau_change_Nm", t.tau_change_Nm, v);
  v("tissue.blend_left", &t.blend_left, 1);
  Matrix("tissue.f_T_W", m.f_T_W, v);
  // The needle through the tissue (tissue.tool: needle; untouched otherwise).
  auto& p = m.puncture;
  v("puncture.num_holes", &p.num_holes, 1);
  Counted(p.holes, p.num_holes, [&](auto& h) {
    Enum("puncture.holes[].status", h.status, v);
    v("puncture.holes[].from_below", &h.from_below, 1);
    Matrix("puncture.holes[].p_SH", h.p_SH, v);
    v("puncture.holes[].s_rad", &h.s_rad, 1);
    v("puncture.holes[].s_anchor_rad", &h.s_anchor_rad, 1);
    v("puncture.holes[].normal_stiffness_N_per_m", &h.normal_stiffness_N_per_m, 1);
    v("puncture.holes[].strain", &h.strain, 1);
    v("puncture.holes[].friction_N", &h.friction_N, 1);
    Matrix("puncture.holes[].f_S", h.f_S, v);
  });
  v("puncture.punctures", &p.punctures, 1);
  v("puncture.pressing", &p.pressing, 1);
  v("puncture.press_N", &p.press_N, 1);
  v("puncture.have_entry", &p.have_entry, 1);
  v("puncture.have_exit", &p.have_exit, 1);
  Matrix("puncture.p_S_entry", p.p_S_entry, v);
  Matrix("puncture.p_S_exit", p.p_S_exit, v);
  v("puncture.peak_strain", &p.peak_strain, 1);
  v("puncture.torn_m", &p.torn_m, 1);
  v("puncture.off_circle_m", &p.off_circle_m, 1);
  v("puncture.peak_press_N", &p.peak_press_N, 1);
  Matrix("puncture.prev_arc.c_S", p.prev_arc.c_S, v);
  Matrix("puncture.prev_arc.e1_S", p.prev_arc.e1_S, v);
  Matrix("puncture.prev_arc.e2_S", p.prev_arc.e2_S, v);
  v("puncture.prev_arc.radius_m", &p.prev_arc.radius_m, 1);
  v("puncture.prev_arc.sweep_rad", &p.prev_arc.sweep_rad, 1);
  v("puncture.have_prev", &p.have_prev, 1);
  v("puncture.warnings", &p.warnings, 1);
  Matrix("puncture.f_S", p.f_S, v);
}

template <typename P, typename V>
void GraspPose(const char* p_name, const char* q_name, P& pose, V& v) {
  Matrix(p_name, pose.p_W, v);
  Matrix(q_name, pose.q_xyzw, v);
}

template <typename S, typename V>
void Grasp(S& m, V& v) {
  auto& g = m.grasp;
  v("grasp.time_s", &g.time_s, 1);
  v("grasp.steps", &g.steps, 1);
  GraspPose("grasp.X_WO.p_W", "grasp.X_WO.q_xyzw", g.X_WO, v);
  Matrix("grasp.v_WO", g.v_WO, v);
  Matrix("grasp.w_WO", g.w_WO, v);
  GraspPose("grasp.X_WT.p_W", "grasp.X_WT.q_xyzw", g.X_WT, v);
  v("grasp.gripper", &g.gripper, 1);
  v("grasp.has_tool", &g.has_tool, 1);
  for (auto& c : g.impulses) {
    v("grasp.impulses[].key", &c.key, 1);
    v("grasp.impulses[].normal_N_s", &c.normal_N_s, 1);
    Matrix("grasp.impulses[].friction_N_s_W", c.friction_N_s_W, v);
  }
  Matrix("grasp.out.f_T_W", g.out.f_T_W, v);
  Matrix("grasp.out.tau_T_W", g.out.tau_T_W, v);
  v("grasp.out.normal_force_N", g.out.normal_force_N.data(), g.out.normal_force_N.size());
  v("grasp.out.max_penetration_m", &g.out.max_penetration_m, 1);
  v("grasp.out.num_contacts", &g.out.num_contacts, 1);
  auto& mt = g.metrics;
  v("grasp.metrics.grasping", &mt.grasping, 1);
  v("grasp.metrics.held", &mt.held, 1);
  v("grasp.metrics.lifted", &mt.lifted, 1);
  v("grasp.metrics.time_since_jaw_contact_s", &mt.time_since_jaw_contact_s, 1);
  GraspPose("grasp.metrics.touch_pose.p_W", "grasp.metrics.touch_pose.q_xyzw", mt.touch_pose, v);
  v("grasp.metrics.induced_rotation_rad", &mt.induced_rotation_rad, 1);
  v("grasp.metrics.max_induced_rotation_rad", &mt.max_induced_rotation_rad, 1);
  v("grasp.metrics.alignment_angle_rad", &mt.alignment_angle_rad, 1);
  v("grasp.metrics.closing_offset_m", &mt.closing_offset_m, 1);
  v("grasp.metrics.grip_force_N", &mt.grip_force_N, 1);
  v("grasp.metrics.peak_grip_force_N", &mt.peak_grip_force_N, 1);
  v("grasp.metrics.held_time_s", &mt.held_time_s, 1);
  v("grasp.metrics.grip_impulse_held_N_s", &mt.grip_impulse_held_N_s, 1);
  v("grasp.metrics.slip_distance_m", &mt.slip_distance_m, 1);
  v("grasp.metrics.grasps", &mt.grasps, 1);
  v("grasp.metrics.lifts", &mt.lifts, 1);
  v("grasp.metrics.drops", &mt.drops, 1);
  v("grasp.warnings.invalid_inputs", &g.warnings.invalid_inputs, 1);
  v("grasp.warnings.nonfinite_resets", &g.warnings.nonfinite_resets, 1);
  v("grasp.warnings.contact_overflows", &g.warnings.contact_overflows, 1);
}

template <typename S, typename V>
void Loop(S& m, V& v) {
  auto& c = m.clearance;
  Enum("loop.clearance.status", c.status, v);
  v("loop.clearance.clearance_m", &c.clearance_m, 1);
  v("loop.clearance.distance_m", &c.distance_m, 1);
  v("loop.clearance.contact", &c.contact, 1);
  Matrix("loop.clearance.p_WA", c.p_WA, v);
  Matrix("loop.clearance.p_WC", c.p_WC, v);
  v("loop.clearance.piece", &c.piece, 1);
  v("loop.clearance.s_m", &c.s_m, 1);
  v("loop.clearance.num_solved", &c.num_solved, 1);
  v("loop.s_m", &m.s_m, 1);
  v("loop.offset_m", &m.offset_m, 1);
  Matrix("loop.p_WA_centre", m.p_WA_centre, v);
  v("loop.warnings", &m.warnings, 1);
}

template <typename S, typename V>
void Knots(S& k, V& v) {
  v("knots.item", &k.item, 1);
  v("knots.item_start_s", &k.item_start_s, 1);
  v("knots.correct", &k.correct, 1);
  v("knots.response_time_sum_s", &k.response_time_sum_s, 1);
  v("knots.last_answer", &k.last_answer, 1);
  v("knots.prev_buttons", &k.prev_buttons, 1);
}

template <typename S, typename V>
void Placement(S& p, V& v) {
  v("placement.count", &p.count, 1);
  const std::size_t n =
      std::min(static_cast<std::size_t>(std::max(p.count, 0)), p.azimuth_rad.size());
  v("placement.azimuth_rad", p.azimuth_rad.data(), n);
  v("placement.bite_m", p.bite_m.data(), n);
  v("placement.prev_buttons", &p.prev_buttons, 1);
}

// An optional section: its presence flag, then its fields when present.
template <typename O, typename V, typename F>
void Section(const char* name, O& section, V& v, F fields) {
  bool present = section.has_value();
  v(name, &present, 1);
  if (section.has_value()) fields(*section, v);
}

}  // namespace visit_internal

template <typename S, typename V>
void VisitStationState(S& s, V& v) {
  static_assert(std::is_same_v<std::remove_const_t<S>, StationState>);
  namespace vi = visit_internal;
  v("step", &s.step, 1);
  v("seed", &s.seed, 1);
  v("rng", &s.rng, 1);
  vi::Tool(s.tool, v);
  vi::Cues(s.cues, v);
  vi::Score(s.score, v);
  vi::Section("second_tool", s.second_tool, v, [](auto& t, V& w) { vi::Tool(t, w, 1); });
  vi::Section("needle", s.needle, v, [](auto& n, V& w) { vi::Needle(n, w); });
  vi::Section("tremor", s.tremor, v, [](auto& t, V& w) { vi::Tremor(t, w); });
  vi::Section("thread", s.thread, v, [](auto& t, V& w) { vi::Thread(t, w); });
  vi::Section("tissue", s.tissue, v, [](auto& t, V& w) { vi::Tissue(t, w); });
  vi::Section("grasp", s.grasp, v, [](auto& g, V& w) { vi::Grasp(g, w); });
  vi::Section("loop", s.loop, v, [](auto& l, V& w) { vi::Loop(l, w); });
  vi::Section("knots", s.knots, v, [](auto& k, V& w) { vi::Knots(k, w); });
  vi::Section("placement", s.placement, v, [](auto& p, V& w) { vi::Placement(p, w); });
}

}  // namespace microdex::state
