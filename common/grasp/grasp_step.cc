#include "common/grasp/grasp_step.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "common/grasp/grasp_contacts.h"
#include "common/grasp/grasp_metrics.h"
#include "common/grasp/grasp_solver.h"

namespace microdex::grasp {
namespace {

Eigen::Isometry3d ToIsometry(const Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = pose.q().toRotationMatrix();
  X.translation() = pose.p_W;
  return X;
}

Eigen::Isometry3d Interpolate(const Pose& a, const Pose& b, double s) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = a.q().slerp(s, b.q()).toRotationMatrix();
  X.translation() = (1.0 - s) * a.p_W + s * b.p_W;
  return X;
}

// Stage: the tool at the end of the step from the device sample. A non-finite pose or gripper
// keeps the last one (counted); the rotation is re-normalised through a quaternion.
bool ReadTool(const GraspInput& in, GraspState& state, Pose& tool, double& gripper) {
  const bool finite = in.X_WT.matrix().allFinite() && std::isfinite(in.gripper);
  if (!finite) {
    ++state.warnings.invalid_inputs;
    tool = state.X_WT;
    gripper = state.gripper;
    return state.has_tool;
  }
  const Eigen::Quaterniond q(in.X_WT.linear());
  const double norm = q.norm();
  if (!(norm > 0.5)) {  // not a rotation
    ++state.warnings.invalid_inputs;
    tool = state.X_WT;
    gripper = state.gripper;
    return state.has_tool;
  }
  tool.p_W = in.X_WT.translation();
  tool.set_q(q.normalized());
  gripper = std::clamp(in.gripper, 0.0, 1.0);
  if (!state.has_tool) {  // the jaws appear at rest
    state.X_WT = tool;
    state.gripper = gripper;
  }
  return true;
}

// Stage: the tool at the start and end of sub-step k of n, and the jaw faces there.
void PlaceJaws(const GraspModel& model, const GraspState& state, const Pose& tool, double gripper,
               int k, int n, GraspWorkspace& w) {
  const double s0 = static_cast<double>(k) / n, s1 = static_cast<double>(k + 1) / n;
  w.X_WT0 = Interpolate(state.X_WT, tool, s0);
  w.X_WT1 = Interpolate(state.X_WT, tool, s1);
  w.gripper0 = (1.0 - s0) * state.gripper + s0 * gripper;
  w.gripper1 = (1.0 - s1) * state.gripper + s1 * gripper;
  w.faces0 = CalcJawFaces(model, w.X_WT0, w.gripper0);
  w.faces1 = CalcJawFaces(model, w.X_WT1, w.gripper1);
}

// Stage: the step's outputs from the impulse sums (means over dt), the deepest contact.
void FinishOutputs(double dt, const GraspWorkspace& w, GraspState& state) {
  GraspOutput& out = state.out;
  for (int pair = 0; pair < kNumPairs; ++pair)
    out.normal_force_N[pair] = w.normal_impulse_N_s[pair] / dt;
  out.f_T_W = w.f_impulse_T_W / dt;
  out.tau_T_W = w.tau_impulse_T_W / dt;
  out.num_contacts = w.num_contacts;
  out.max_penetration_m = 0.0;
  for (int i = 0; i < w.num_contacts; ++i) {
    out.max_penetration_m = std::max(out.max_penetration_m, -w.contacts[i].separation_m);
  }
}

bool Finite(const GraspState& state) {
  return state.X_WO.p_W.allFinite() && state.X_WO.q_xyzw.allFinite() && state.v_WO.allFinite() &&
         state.w_WO.allFinite() && state.out.f_T_W.allFinite() && state.out.tau_T_W.allFinite();
}

}  // namespace

void StepGrasp(const GraspModel& model, const GraspInput& in, GraspWorkspace& w,
               GraspState& state) {
  const double dt = in.dt_s;
  if (!(std::isfinite(dt) && dt > 0.0 && dt <= model.def.max_time_step_s)) {
    ++state.warnings.invalid_inputs;
    return;
  }
  Pose tool;
  double gripper = 0.0;
  const bool has_jaws = ReadTool(in, state, tool, gripper);
  w.X_WO_start = state.X_WO;

  w.warm = state.impulses;
  w.normal_impulse_N_s.fill(0.0);
  w.f_impulse_T_W.setZero();
  w.tau_impulse_T_W.setZero();
  w.slip_m = 0.0;
  w.overflows = 0;
  const int n = model.def.solver.substeps;
  const double h = dt / n;
  for (int k = 0; k < n; ++k) {
    ClearContacts(w);
    ContactsFromTable(model, state, h, w);
    if (has_jaws) {
      PlaceJaws(model, state, tool, gripper, k, n, w);
      ContactsFromJaws(model, state, h, w);
    } else {
      w.X_WT0 = w.X_WT1 = ToIsometry(state.X_WT);
    }
    ApplyFreeMotion(model, h, state);
    SolveContacts(model, h, w, state);
    IntegratePose(h, state);
  }
  state.impulses = w.warm;
  state.warnings.contact_overflows += w.overflows;
  FinishOutputs(dt, w, state);
  if (!Finite(state)) {
    ++state.warnings.nonfinite_resets;
    state.X_WO = w.X_WO_start;
    state.v_WO.setZero();
    state.w_WO.setZero();
    state.impulses = {};
    state.out = GraspOutput{};
  }
  if (has_jaws) {
    state.X_WT = tool;
    state.gripper = gripper;
    state.has_tool = true;
  }
  UpdateMetrics(model, dt, w, state);
  state.time_s += dt;
  ++state.steps;
}

}  // namespace microdex::grasp
