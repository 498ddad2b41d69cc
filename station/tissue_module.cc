#include "station/tissue_module.h"

#include <cmath>
#include <utility>

#include "common/base/check.h"

namespace microdex::station {

TissueModule::TissueModule(const scene::SceneModel& scene, SharedStitch stitch)
    : model_(fem::BuildTissueModel(scene.tissue->def)),
      ws_(model_),
      X_SW_(scene.tissue->X_WS.inverse()),
      R_WS_(scene.tissue->X_WS.linear()),
      tool_kind_(scene.tissue->tool),
      puncture_(scene.puncture),
      X_TN_(scene.X_TN()),
      needle_radius_m_(scene.needle.radius_m),
      needle_sweep_rad_(scene.needle.sweep_rad),
      contact_radius_m_(scene.tissue->contact_radius_m),
      half_bar_m_(0.5 * scene.tissue->bar_length_m),
      display_level_(scene.tissue->display_level),
      max_force_N_(scene.tissue->max_force_N),
      stitch_(stitch ? std::move(stitch) : MakeSharedStitchOnTissue(scene)) {
  const std::size_t side = (std::size_t{1} << display_level_) + 1;
  MICRODEX_CHECK(side * side <= kMaxFrameTissueNodes);  // display_level <= 6 (scene)
  grid_m_.assign(side * side, 0.0);
  field_scratch_m_.assign(model_.num_grid_nodes, 0.0);
}

void TissueModule::InitState(state::StationState& s) const {
  s.tissue = state::TissueModuleState{fem::MakeTissueState(model_), Eigen::Vector3d::Zero()};
}

void TissueModule::Step(const ToolInput& in, state::StationState& s, Eigen::Vector3d& f_T_W) {
  state::TissueModuleState& t = *s.tissue;
  if (tool_kind_ == scene::TissueToolKind::kNeedle) {
    const Eigen::Isometry3d X_SN = X_SW_ * in.X_WT * X_TN_;
    puncture::NeedleArc arc;
    arc.c_S = X_SN.translation();
    arc.e1_S = X_SN.linear().col(0);
    arc.e2_S = X_SN.linear().col(1);
    arc.radius_m = needle_radius_m_;
    arc.sweep_rad = needle_sweep_rad_;
    const std::uint32_t step_before = t.tissue.step;
    puncture::StepPuncture(puncture_->def, model_, arc, ws_, t.tissue, t.puncture);
    if (t.tissue.step != step_before && (!ws_.stats.pattern_reused || ws_.stats.mesh_moved))
      ++mesh_revision_;
    t.f_T_W = R_WS_ * t.puncture.f_S;
    if (!t.f_T_W.allFinite()) t.f_T_W.setZero();
    f_T_W += t.f_T_W;
    return;
  }
  Eigen::Vector3d p_ST = X_SW_ * in.X_WT.translation();
  if (stitch_ && s.thread) {
    // The surface under the tool as the stitch's loads have displaced it.
    const std::array<double, kStitchRods>& load_N = s.thread->tie.stitch_load_N;
    double w_m = 0;
    for (int k = 0; k < kStitchRods; ++k) {
      w_m += load_N[static_cast<std::size_t>(k)] *
             fem::SampleGrid(model_, stitch_->compliance.grid_m_per_N[static_cast<std::size_t>(k)],
                             display_level_, p_ST.x(), p_ST.y());
    }
    if (std::isfinite(w_m)) p_ST.z() -= w_m;
  }
  if (tool_kind_ == scene::TissueToolKind::kPoint) {
    tool_ = fem::MakePointTool(p_ST, contact_radius_m_);
  } else {
    const Eigen::Vector3d u_S = X_SW_.linear() * in.X_WT.linear().col(0);
    tool_ = fem::MakeBarTool(p_ST - half_bar_m_ * u_S, p_ST + half_bar_m_ * u_S);
  }
  fem::StepTissue(model_, tool_, ws_, t.tissue);
  // A new selection, or the attached mesh's nodes moved with the tool.
  if (!ws_.stats.pattern_reused || ws_.stats.mesh_moved) ++mesh_revision_;
  // A failed step keeps the last good field and force (StepTissue), so the force stays
  // continuous; the failure is counted in the state's num_failed_steps.
  t.f_T_W = R_WS_ * t.tissue.f_T_S;
  if (!t.f_T_W.allFinite()) t.f_T_W.setZero();
  f_T_W += t.f_T_W;
}

ModuleStatus TissueModule::Status(const state::StationState& s) const {
  const state::TissueModuleState& t = *s.tissue;
  ModuleStatus out;
  out.fault = t.f_T_W.norm() > max_force_N_;
  if (puncture_) {
    // A hole at its tear strain is tearing.
    const double tearing = puncture_->def.tear_strain * (1 - 1e-9);
    for (int i = 0; i < t.puncture.num_holes; ++i) {
      const puncture::Hole& h = t.puncture.holes[i];
      out.fault = out.fault || (h.status == puncture::HoleStatus::kOpen && h.strain >= tearing);
    }
  }
  out.fault_value = t.f_T_W.norm();
  out.error_estimate = ws_.stats.relative_residual;
  out.warnings = t.tissue.num_failed_steps;
  return out;
}

void TissueModule::WriteFrame(const state::StationState& s, std::uint64_t step,
                              std::int64_t stamp_ns, LargeFrames& frames) {
  const fem::TissueState& state = s.tissue->tissue;
  TissueFrame& f = frames.tissue.back();
  // Same sizes every call: no allocation.
  fem::CalcDisplacementGrid(model_, state, display_level_, field_scratch_m_, grid_m_);
  const std::uint32_t side = (1u << display_level_) + 1;
  f.step = step;
  f.stamp_ns = stamp_ns;
  f.nodes_x = side;
  f.nodes_y = side;
  f.mesh_revision = mesh_revision_;
  f.unknowns = static_cast<std::uint32_t>(ws_.stats.unknowns);
  f.status = state.status;
  // The field is harmonic off the contact nodes and zero on the edges, so its largest
  // magnitude is at a contact node (maximum principle).
  double w_max = 0;
  for (int c = 0; c < state.num_contacts; ++c) {
    w_max = std::max(w_max, std::abs(field_scratch_m_[state.contact_nodes[c]]));
  }
  if (stitch_ && s.thread) {
    // Knot tying: the stitch's loads' field, whose largest magnitude is at a rod.
    const std::array<double, kStitchRods>& load_N = s.thread->tie.stitch_load_N;
    for (int k = 0; k < kStitchRods; ++k) {
      const double f_N = load_N[static_cast<std::size_t>(k)];
      const std::vector<double>& g = stitch_->compliance.grid_m_per_N[static_cast<std::size_t>(k)];
      if (!std::isfinite(f_N) || f_N == 0) continue;
      for (std::size_t i = 0; i < grid_m_.size(); ++i) grid_m_[i] += f_N * g[i];
    }
    const Eigen::Vector3d w_rods_m = stitch_->Displacement_m(load_N);
    if (w_rods_m.allFinite()) w_max = std::max(w_max, w_rods_m.cwiseAbs().maxCoeff());
  }
  for (std::size_t i = 0; i < grid_m_.size(); ++i) f.w_m[i] = static_cast<float>(grid_m_[i]);
  f.max_displacement_m = w_max;
  frames.tissue.Publish();
}

}  // namespace microdex::station
