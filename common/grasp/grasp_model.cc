#include "common/grasp/grasp_model.h"

#include <algorithm>
#include <cmath>

namespace microdex::grasp {

GraspModel MakeGraspModel(const GraspDef& def) {
  def.Validate();
  GraspModel model;
  model.def = def;
  model.shape = MakeShapeGeometry(def.shape);
  const MassProperties mp = CalcMassProperties(def.shape, def.density_kg_per_m3);
  model.mass_kg = mp.mass_kg;
  model.inertia_kg_m2 = mp.inertia_kg_m2;
  model.inv_inertia_per_kg_m2 = mp.inertia_kg_m2.cwiseInverse();
  model.weight_N = mp.mass_kg * def.gravity_m_per_s2.norm();
  const double k[kNumPairs] = {def.contact.table_stiffness_N_per_m,
                               def.contact.jaw_stiffness_N_per_m,
                               def.contact.jaw_stiffness_N_per_m};
  for (int pair = 0; pair < kNumPairs; ++pair) {
    model.stiffness_N_per_m[pair] = k[pair];
    // A fraction of the critical damping 2 sqrt(k m) of the object on the pair's spring.
    model.damping_N_s_per_m[pair] =
        2.0 * def.contact.damping_ratio * std::sqrt(k[pair] * model.mass_kg);
  }
  model.friction = {def.table_friction, def.jaw_friction, def.jaw_friction};
  return model;
}

double CalcLowestPoint(const GraspModel& model, const Eigen::Vector3d& p_WO,
                       const Eigen::Quaterniond& q_WO) {
  const Eigen::Matrix3d R_WO = q_WO.toRotationMatrix();
  const Eigen::Vector3d down_O = R_WO.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  std::array<Eigen::Vector3d, kMaxSupportPoints> points_O;
  const int n = CalcSupportPoints(model.shape, down_O, points_O);
  double lowest = p_WO.z() + model.shape.bounding_radius_m;
  for (int k = 0; k < n; ++k) lowest = std::min(lowest, (p_WO + R_WO * points_O[k]).z());
  return lowest;
}

GraspState MakeGraspStateOnTable(const GraspModel& model, const Eigen::Vector3d& p_W,
                                 const Eigen::Quaterniond& q_WO) {
  GraspState state;
  const Eigen::Quaterniond q = q_WO.normalized();
  Eigen::Vector3d p(p_W.x(), p_W.y(), 0.0);
  p.z() = -CalcLowestPoint(model, p, q);
  state.X_WO.p_W = p;
  state.X_WO.set_q(q);
  return state;
}

}  // namespace microdex::grasp
