#include "common/grasp/grasp_contacts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace microdex::grasp {
namespace {

// The speculative margin of a sub-step: the def's margin plus the farthest the object's surface
// can move in it.
double Margin(const GraspModel& model, const GraspState& state, double h) {
  return model.def.contact.speculative_margin_m +
         h * (state.v_WO.norm() + state.w_WO.norm() * model.shape.bounding_radius_m);
}

bool Push(GraspWorkspace& w, const Contact& c) {
  if (w.num_contacts >= kMaxContacts) {
    ++w.overflows;
    return false;
  }
  w.contacts[w.num_contacts++] = c;
  return true;
}

// The pose of jaw j (0: +, 1: -): the tool pose moved by the half gap along y_T; its face
// normal is -y_J for jaw + and +y_J for jaw -.
Eigen::Isometry3d JawPose(const Eigen::Isometry3d& X_WT, double half_gap, int j) {
  Eigen::Isometry3d X_WJ = X_WT;
  X_WJ.translate(Eigen::Vector3d(0.0, j == 0 ? half_gap : -half_gap, 0.0));
  return X_WJ;
}

// Clips the segment a + t (b - a), t in [t0, t1], to the band |axis . (p - centre)| <= half.
bool ClipToBand(const Eigen::Vector3d& axis, const Eigen::Vector3d& centre, double half,
                const Eigen::Vector3d& a, const Eigen::Vector3d& b, double& t0, double& t1) {
  const double pa = axis.dot(a - centre), d = axis.dot(b - a);
  if (std::abs(d) < 1e-300) return std::abs(pa) <= half;
  double lo = (-half - pa) / d, hi = (half - pa) / d;
  if (lo > hi) std::swap(lo, hi);
  t0 = std::max(t0, lo);
  t1 = std::min(t1, hi);
  return t0 <= t1;
}

// An edge end this close to a vertex (in edge parameter) is the vertex itself.
constexpr double kUnclipped = 1e-9;

}  // namespace

double CalcHalfGap(const JawDef& jaws, double gripper) {
  const double g = std::clamp(gripper, 0.0, 1.0);
  return 0.5 * ((1.0 - g) * jaws.open_gap_m + g * jaws.closed_gap_m);
}

std::array<JawFace, 2> CalcJawFaces(const GraspModel& model, const Eigen::Isometry3d& X_WT,
                                    double gripper) {
  const double half_gap = CalcHalfGap(model.def.jaws, gripper);
  const Eigen::Matrix3d R_WT = X_WT.linear();
  std::array<JawFace, 2> faces;
  for (int j = 0; j < 2; ++j) {
    faces[j].c_W = JawPose(X_WT, half_gap, j).translation();
    faces[j].n_W = (j == 0 ? -1.0 : 1.0) * R_WT.col(1);
    faces[j].u_W = R_WT.col(0);
    faces[j].w_W = R_WT.col(2);
  }
  return faces;
}

void ClearContacts(GraspWorkspace& w) { w.num_contacts = 0; }

void ContactsFromTable(const GraspModel& model, const GraspState& state, double h,
                       GraspWorkspace& w) {
  const Eigen::Matrix3d R_WO = state.X_WO.q().toRotationMatrix();
  const Eigen::Vector3d& p_WO = state.X_WO.p_W;
  const Eigen::Vector3d down_O = R_WO.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  std::array<Eigen::Vector3d, kMaxSupportPoints> points_O;
  const int n = CalcSupportPoints(model.shape, down_O, points_O);
  const double margin = Margin(model, state, h);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p_W = p_WO + R_WO * points_O[k];
    if (!(p_W.z() < margin)) continue;
    Contact c;
    c.pair = kTablePair;
    c.key = kTablePair * kKeysPerPair + k;
    c.p_W = p_W;
    c.n_W = Eigen::Vector3d::UnitZ();
    c.separation_m = p_W.z();
    if (!Push(w, c)) return;
  }
}

void ContactsFromJaws(const GraspModel& model, const GraspState& state, double h,
                      GraspWorkspace& w) {
  const JawDef& jaws = model.def.jaws;
  const Eigen::Matrix3d R_WO = state.X_WO.q().toRotationMatrix();
  const Eigen::Vector3d& p_WO = state.X_WO.p_W;
  const double margin = Margin(model, state, h);
  const double half_width = 0.5 * jaws.width_m, half_length = 0.5 * jaws.length_m;
  const double half_gap0 = CalcHalfGap(jaws, w.gripper0);
  const double half_gap1 = CalcHalfGap(jaws, w.gripper1);
  // How far any point of a face moves in the sub-step: the region behind a face that counts as
  // inside the jaw grows by it, so a fast jaw cannot pass over the object's surface.
  const double tool_turn_rad =
      Eigen::AngleAxisd(w.X_WT1.linear() * w.X_WT0.linear().transpose()).angle();
  const double reach_m = std::hypot(std::max(std::abs(half_gap0), std::abs(half_gap1)),
                                    std::hypot(half_width, half_length));
  std::array<Eigen::Vector3d, kMaxSupportPoints> points_O;
  for (int j = 0; j < 2; ++j) {
    const int pair = j == 0 ? kJawPlusPair : kJawMinusPair;
    const JawFace& f = w.faces1[j];
    const Eigen::Isometry3d X_WJ0 = JawPose(w.X_WT0, half_gap0, j);
    const Eigen::Isometry3d X_WJ1 = JawPose(w.X_WT1, half_gap1, j);
    const Eigen::Isometry3d X_J0J1 = X_WJ0 * X_WJ1.inverse();  // end to start, world points
    const double sweep_m = (w.faces1[j].c_W - w.faces0[j].c_W).norm() + tool_turn_rad * reach_m;
    const double deepest = -(jaws.thickness_m + sweep_m);
    auto velocity_at = [&](const Eigen::Vector3d& p_W) -> Eigen::Vector3d {
      return (p_W - X_J0J1 * p_W) / h;
    };
    // The object's support points over the face.
    const int n = CalcSupportPoints(model.shape, R_WO.transpose() * (-f.n_W), points_O);
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d p_W = p_WO + R_WO * points_O[k];
      const Eigen::Vector3d d = p_W - f.c_W;
      const double s = f.n_W.dot(d);
      if (!(s < margin && s > deepest)) continue;
      if (std::abs(f.u_W.dot(d)) > half_width || std::abs(f.w_W.dot(d)) > half_length) continue;
      Contact c;
      c.pair = pair;
      c.key = pair * kKeysPerPair + k;
      c.p_W = p_W;
      c.n_W = f.n_W;
      c.separation_m = s;
      c.v_other_W = velocity_at(p_W);
      if (!Push(w, c)) return;
    }
    // The object's edges clipped to the face's sides: where an edge leaves the face sideways
    // (an edge across the face, or a box edge on a jaw narrower than the box), the clipped end
    // is a contact; unclipped ends are support points, already in.
    SupportEdges edges;
    const int num_edges = CalcSupportEdges(model.shape, edges);
    for (int e = 0; e < num_edges; ++e) {
      const Eigen::Vector3d a_W = p_WO + R_WO * points_O[edges[e][0]];
      const Eigen::Vector3d b_W = p_WO + R_WO * points_O[edges[e][1]];
      double t0 = 0.0, t1 = 1.0;
      if (!ClipToBand(f.u_W, f.c_W, half_width, a_W, b_W, t0, t1)) continue;
      if (!ClipToBand(f.w_W, f.c_W, half_length, a_W, b_W, t0, t1)) continue;
      for (int end = 0; end < 2; ++end) {
        const double t = end == 0 ? t0 : t1;
        if (!(t > kUnclipped && t < 1.0 - kUnclipped)) continue;
        const Eigen::Vector3d p_W = a_W + t * (b_W - a_W);
        const double s = f.n_W.dot(p_W - f.c_W);
        if (!(s < margin && s > deepest)) continue;
        Contact c;
        c.pair = pair;
        c.key = pair * kKeysPerPair + kMaxSupportPoints + kJawLineSamples + 2 * e + end;
        c.p_W = p_W;
        c.n_W = f.n_W;
        c.separation_m = s;
        c.v_other_W = velocity_at(p_W);
        if (!Push(w, c)) return;
      }
    }
    // Lines from the face's corners, edge midpoints and centre along its normal: where one
    // enters the object behind the face (or within the margin in front of it), the object's
    // entry point is a contact.
    const Eigen::Vector3d d_O = R_WO.transpose() * f.n_W;
    for (int k = 0; k < kJawLineSamples; ++k) {
      const int column = k % 3, row = k / 3;
      const double a = static_cast<double>(column - 1) * half_width;
      const double b = static_cast<double>(row - 1) * half_length;
      const Eigen::Vector3d q_W = f.c_W + a * f.u_W + b * f.w_W;
      double s_in = 0.0, s_out = 0.0;
      if (!CalcLineInterval(model.shape, R_WO.transpose() * (q_W - p_WO), d_O, s_in, s_out)) {
        continue;
      }
      if (!(s_in < margin && s_in > deepest && s_out > 0.0)) continue;
      Contact c;
      c.pair = pair;
      c.key = pair * kKeysPerPair + kMaxSupportPoints + k;
      c.p_W = q_W + s_in * f.n_W;
      c.n_W = f.n_W;
      c.separation_m = s_in;
      c.v_other_W = velocity_at(c.p_W);
      if (!Push(w, c)) return;
    }
  }
}

}  // namespace microdex::grasp
