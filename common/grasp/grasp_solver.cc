#include "common/grasp/grasp_solver.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace microdex::grasp {
namespace {

// A flat face rests on four points: each point gets a quarter of its pair's spring and damper.
constexpr double kPointsPerFace = 4.0;

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

struct Body {
  double inv_mass = 0.0;
  Eigen::Matrix3d inv_inertia_W = Eigen::Matrix3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  void Apply(const Eigen::Vector3d& r, const Eigen::Vector3d& impulse) {
    v += inv_mass * impulse;
    w += inv_inertia_W * r.cross(impulse);
  }
  Eigen::Vector3d PointVelocity(const Eigen::Vector3d& r) const { return v + w.cross(r); }
};

const ContactImpulse* FindWarm(const GraspWorkspace& w, int key) {
  for (const ContactImpulse& c : w.warm) {
    if (c.key == key) return &c;
  }
  return nullptr;
}

// The solver's per-contact constants: lever arm, tangents, effective masses, spring terms.
void PrepareContact(const GraspModel& model, const Body& body, const Eigen::Vector3d& p_WO,
                    double h, Contact& c) {
  c.r_W = c.p_W - p_WO;
  const Eigen::Vector3d axis =
      std::abs(c.n_W.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  c.t1_W = c.n_W.cross(axis).normalized();
  c.t2_W = c.n_W.cross(c.t1_W);
  const Eigen::Vector3d rn = c.r_W.cross(c.n_W);
  c.normal_mass_kg = 1.0 / (body.inv_mass + rn.dot(body.inv_inertia_W * rn));
  const Eigen::Vector3d rt1 = c.r_W.cross(c.t1_W), rt2 = c.r_W.cross(c.t2_W);
  Eigen::Matrix2d k;
  k(0, 0) = body.inv_mass + rt1.dot(body.inv_inertia_W * rt1);
  k(1, 1) = body.inv_mass + rt2.dot(body.inv_inertia_W * rt2);
  k(0, 1) = k(1, 0) = rt1.dot(body.inv_inertia_W * rt2);
  c.tangent_mass_kg = k.inverse();
  const double mean = 0.5 * (k(0, 0) + k(1, 1));
  const double spread = std::hypot(0.5 * (k(0, 0) - k(1, 1)), k(0, 1));
  c.slide_mass_kg = 1.0 / (mean + spread);
  // Implicit spring and damper: the impulse over h is lambda = -h k (C + h Cdot+) - h c Cdot+,
  // i.e. the row Cdot+ + bias + softness lambda = 0 with softness 1 / (h (h k + c)) and
  // bias k C / (h k + c) (Catto, "Soft Constraints", GDC 2011; ODE's ERP/CFM).
  // The stiffness a step resolves: at most stiffness_limit m_eff / h^2 (Box2D v3 likewise
  // bounds its contact frequency by the sub-step rate). Stiffer springs on light objects were
  // measured to pump energy when a rotating object is squeezed between the jaws: the implicit
  // spring is stable only for the linearised contact geometry.
  // The table pushes from one side only and takes a higher limit (its sag under the weight,
  // at most g h^2 / limit, stays about a micrometre at 1 kHz).
  const double ratio = c.pair == kTablePair ? model.def.contact.table_stiffness_limit
                                            : model.def.contact.jaw_stiffness_limit;
  const double k_limit = ratio * c.normal_mass_kg / (h * h);
  const double k_point = std::min(model.stiffness_N_per_m[c.pair] / kPointsPerFace, k_limit);
  const double c_point =
      2.0 * model.def.contact.damping_ratio * std::sqrt(k_point * c.normal_mass_kg);
  const double hk_c = h * k_point + c_point;
  c.softness = 1.0 / (h * hk_c);
  c.bias_m_per_s = k_point * c.separation_m / hk_c;
}

}  // namespace

void ApplyFreeMotion(const GraspModel& model, double h, GraspState& state) {
  state.v_WO += h * model.def.gravity_m_per_s2;
  // Gyroscopic term, implicit: I (w+ - w) + h w+ x I w+ = 0 in the body frame, one Newton
  // step from w (as Bullet's and Box2D's solvers do): stable for spinning slender bodies.
  const Eigen::Matrix3d R_WO = state.X_WO.q().toRotationMatrix();
  const Eigen::Vector3d w_B = R_WO.transpose() * state.w_WO;
  const Eigen::Matrix3d I = model.inertia_kg_m2.asDiagonal();
  const Eigen::Vector3d Iw = I * w_B;
  const Eigen::Vector3d f = h * w_B.cross(Iw);
  const Eigen::Matrix3d J = I + h * (Skew(w_B) * I - Skew(Iw));
  const Eigen::Vector3d w_new = w_B - J.partialPivLu().solve(f);
  state.w_WO = R_WO * w_new;
}

void SolveContacts(const GraspModel& model, double h, GraspWorkspace& w, GraspState& state) {
  const Eigen::Matrix3d R_WO = state.X_WO.q().toRotationMatrix();
  Body body;
  body.inv_mass = 1.0 / model.mass_kg;
  body.inv_inertia_W = R_WO * model.inv_inertia_per_kg_m2.asDiagonal() * R_WO.transpose();
  body.v = state.v_WO;
  body.w = state.w_WO;
  const Eigen::Vector3d& p_WO = state.X_WO.p_W;
  const int n = w.num_contacts;
  // Warm start from the last sub-step's impulses of the same contacts.
  for (int i = 0; i < n; ++i) {
    Contact& c = w.contacts[i];
    PrepareContact(model, body, p_WO, h, c);
    c.normal_N_s = 0.0;
    c.friction_N_s.setZero();
    const ContactImpulse* warm = FindWarm(w, c.key);
    if (warm == nullptr) continue;
    c.normal_N_s = std::max(0.0, warm->normal_N_s);
    Eigen::Vector2d p(c.t1_W.dot(warm->friction_N_s_W), c.t2_W.dot(warm->friction_N_s_W));
    const double bound = model.friction[c.pair] * c.normal_N_s;
    const double norm = p.norm();
    if (norm > bound) p *= norm > 0.0 ? bound / norm : 0.0;
    c.friction_N_s = p;
    body.Apply(c.r_W, c.normal_N_s * c.n_W + p.x() * c.t1_W + p.y() * c.t2_W);
  }
  // Projected Gauss–Seidel: each normal row solves its soft constraint and is clamped to
  // pushing; each friction pair stops the contact's slip and is projected onto the Coulomb disc
  // |p_t| <= mu p_n.
  // (Alternating forward and backward sweeps was tried and left a symmetric grasp turned by
  // about three times more at 20 iterations.)
  for (int it = 0; it < model.def.solver.iterations; ++it) {
    for (int i = 0; i < n; ++i) {
      Contact& c = w.contacts[i];
      const double vn = c.n_W.dot(body.PointVelocity(c.r_W));
      const double dn = -(vn + c.bias_m_per_s + c.softness * c.normal_N_s) /
                        (1.0 / c.normal_mass_kg + c.softness);
      const double pn = std::max(0.0, c.normal_N_s + dn);
      body.Apply(c.r_W, (pn - c.normal_N_s) * c.n_W);
      c.normal_N_s = pn;

      const double mu = model.friction[c.pair];
      const Eigen::Vector3d v_rel = body.PointVelocity(c.r_W) - c.v_other_W;
      const Eigen::Vector2d vt(c.t1_W.dot(v_rel), c.t2_W.dot(v_rel));
      // Sticking: the 2x2 block stops the slip exactly. Sliding: a step with a scalar mass
      // (1 / the block's largest inverse mass) projected onto the disc, whose fixed point has
      // the friction exactly opposite the slip (maximal dissipation); projecting the block
      // step instead tilts the friction off the slip and was measured to spin a sliding box.
      Eigen::Vector2d pt = c.friction_N_s - c.tangent_mass_kg * vt;
      const double bound = mu * pn;
      if (pt.norm() > bound) {
        pt = c.friction_N_s - c.slide_mass_kg * vt;
        const double norm = pt.norm();
        pt *= norm > bound ? bound / norm : 1.0;
      }
      const Eigen::Vector2d dt = pt - c.friction_N_s;
      body.Apply(c.r_W, dt.x() * c.t1_W + dt.y() * c.t2_W);
      c.friction_N_s = pt;
    }
  }
  state.v_WO = body.v;
  state.w_WO = body.w;
  // Impulses out: warm start of the next sub-step and the step's sums.
  const Eigen::Vector3d p_WT = w.X_WT1.translation();
  double slip_weighted = 0.0, jaw_normal = 0.0;
  for (int i = 0; i < kMaxContacts; ++i) {
    ContactImpulse& out = w.warm[i];
    if (i >= n) {
      out = ContactImpulse{};
      continue;
    }
    const Contact& c = w.contacts[i];
    const Eigen::Vector3d friction_W = c.friction_N_s.x() * c.t1_W + c.friction_N_s.y() * c.t2_W;
    out.key = c.key;
    out.normal_N_s = c.normal_N_s;
    out.friction_N_s_W = friction_W;
    w.normal_impulse_N_s[c.pair] += c.normal_N_s;
    if (c.pair == kTablePair) continue;
    const Eigen::Vector3d on_tool = -(c.normal_N_s * c.n_W + friction_W);
    w.f_impulse_T_W += on_tool;
    w.tau_impulse_T_W += (c.p_W - p_WT).cross(on_tool);
    const Eigen::Vector3d v_rel = body.PointVelocity(c.r_W) - c.v_other_W;
    slip_weighted += c.normal_N_s * (v_rel - c.n_W.dot(v_rel) * c.n_W).norm();
    jaw_normal += c.normal_N_s;
  }
  if (jaw_normal > 0.0) w.slip_m += h * slip_weighted / jaw_normal;
}

void IntegratePose(double h, GraspState& state) {
  state.X_WO.p_W += h * state.v_WO;
  const double angle = h * state.w_WO.norm();
  Eigen::Quaterniond q = state.X_WO.q();
  if (angle > 0.0) {
    q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, state.w_WO.normalized())) * q;
  }
  state.X_WO.set_q(q.normalized());
}

}  // namespace microdex::grasp
