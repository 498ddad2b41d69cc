#include "common/thread/thread_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/base/check.h"

namespace microdex::thread {

ThreadModel MakeThreadModel(const ThreadDef& def) {
  def.Validate();
  ThreadModel m;
  m.def = def;
  m.num_nodes = def.num_nodes;
  m.num_links = def.num_nodes - 1;
  m.radius_m = 0.5 * def.diameter_m;
  const double rest_m = def.length_m / m.num_links;
  const double d = def.diameter_m;
  const double area_m2 = std::numbers::pi * d * d / 4.0;
  const double second_moment_m4 = std::numbers::pi * d * d * d * d / 64.0;
  const double polar_moment_m4 = 2.0 * second_moment_m4;

  m.rest_length_m = Eigen::VectorXd::Constant(m.num_links, rest_m);
  m.stretch_k_N_per_m = Eigen::VectorXd::Constant(
      m.num_links, def.stretch_stiffness_N_per_m > 0.0 ? def.stretch_stiffness_N_per_m
                                                       : def.youngs_modulus_Pa * area_m2 / rest_m);
  m.twist_k_N_m = Eigen::VectorXd::Constant(
      m.num_links, def.twist_stiffness_N_m > 0.0 ? def.twist_stiffness_N_m
                                                 : def.shear_modulus_Pa * polar_moment_m4 / rest_m);
  m.bend_k_N_m = Eigen::VectorXd::Zero(m.num_nodes);
  m.mass_kg = Eigen::VectorXd::Zero(m.num_nodes);
  m.drag_N_s_per_m = Eigen::VectorXd::Zero(m.num_nodes);
  for (int i = 0; i < m.num_nodes; ++i) {
    // A node carries half of each adjacent link.
    const double left = i > 0 ? m.rest_length_m[i - 1] : 0.0;
    const double right = i < m.num_links ? m.rest_length_m[i] : 0.0;
    const double share_m = 0.5 * (left + right);
    if (i > 0 && i < m.num_nodes - 1) {
      m.bend_k_N_m[i] = def.bend_stiffness_N_m > 0.0
                            ? def.bend_stiffness_N_m
                            : def.youngs_modulus_Pa * second_moment_m4 / share_m;
    }
    const double mass =
        def.node_mass_kg > 0.0 ? def.node_mass_kg : def.density_kg_per_m3 * area_m2 * share_m;
    m.mass_kg[i] = mass * def.mass_scale;
    m.drag_N_s_per_m[i] = def.drag_N_s_per_m2 * share_m;
  }
  m.inertia_kg_m2 = 0.5 * m.mass_kg * m.radius_m * m.radius_m;
  m.bvh = BuildSphereBvhTopology(m.num_links);
  m.bvh_inflate_m = m.radius_m + def.contact_cutoff_m + 0.5 * def.diameter_m;
  m.contact_capacity = def.max_contacts > 0 ? def.max_contacts : 16 * m.num_links;
  m.half_bandwidth = 8;
  m.exact_pair_capacity = std::min(def.exact_contact_pairs, m.contact_capacity);
  m.friction_capacity = def.friction_coefficient > 0.0 || def.object_friction_coefficient > 0.0
                            ? std::min(def.friction_contacts, 2 * m.contact_capacity)
                            : 0;
  m.friction_self_capacity = std::min(m.friction_capacity, def.friction_self_contacts);
  return m;
}

ThreadState MakeThreadState(const ThreadModel& model, const Eigen::Matrix3Xd& x_W) {
  MICRODEX_CHECK(x_W.cols() == model.num_nodes);
  const int n = model.num_nodes;
  ThreadState s;
  s.x_W = x_W;
  s.v_W = Eigen::Matrix3Xd::Zero(3, n);
  s.q_rad = Eigen::VectorXd::Zero(n);
  s.qdot_rad_per_s = Eigen::VectorXd::Zero(n);
  s.grasps.assign(model.def.max_grasps, Grasp{});
  return s;
}

ThreadWorkspace MakeThreadWorkspace(const ThreadModel& model) {
  const int n = model.num_nodes;
  ThreadWorkspace w;
  w.f_W = Eigen::Matrix3Xd::Zero(3, n);
  w.x_prev_W = Eigen::Matrix3Xd::Zero(3, n);
  w.x_end_W = Eigen::Matrix3Xd::Zero(3, n);
  w.x_part_W = Eigen::Matrix3Xd::Zero(3, n);
  w.v_prev_W = Eigen::Matrix3Xd::Zero(3, n);
  w.q_prev_rad = Eigen::VectorXd::Zero(n);
  w.qdot_prev_rad_per_s = Eigen::VectorXd::Zero(n);
  w.tau_N_m = Eigen::VectorXd::Zero(n);
  w.k_contact = Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, n);
  w.c_contact_N_s_per_m = Eigen::VectorXd::Zero(n);
  w.grasp_slot = Eigen::VectorXi::Constant(n, -1);
  w.spheres = MakeSphereBvhSpheres(model.bvh);
  w.pairs.assign(model.contact_capacity, LinkPair{});
  w.swept_pairs.assign(model.contact_capacity, LinkPair{});
  w.pair_start.assign(model.contact_capacity, PairStart{});
  w.object_candidates.assign(model.contact_capacity, LinkPair{});
  w.inverse_mass = Eigen::VectorXd::Zero(n);
  w.node_moved_at = Eigen::VectorXi::Zero(n);
  w.pair_checked_at = Eigen::VectorXi::Zero(model.contact_capacity);
  w.object_checked_at = Eigen::VectorXi::Zero(model.contact_capacity);
  w.node_travel_m = Eigen::VectorXd::Zero(n);
  w.pair_clear_m = Eigen::VectorXd::Zero(model.contact_capacity);
  w.strain_band = MakeStrainBandScratch(model.num_links);
  w.self_contacts.assign(model.contact_capacity, SelfContact{});
  w.object_contacts.assign(model.contact_capacity, ObjectContact{});
  w.system = BandedSpd(3 * n, model.half_bandwidth);
  w.twist_system = BandedSpd(n, 1);
  w.rhs = Eigen::VectorXd::Zero(3 * n);
  w.twist_rhs = Eigen::VectorXd::Zero(n);
  w.grasp_rows = Eigen::MatrixXd::Zero(3 * model.def.max_grasps, 2 * model.half_bandwidth + 2);
  const int pairs = model.exact_pair_capacity;
  const int friction = model.friction_capacity;
  w.low_rank = LowRankSolver(3 * n, pairs + 2 * friction);
  w.columns.assign(pairs + 2 * friction, NodeColumn{});
  w.friction_columns.assign(2 * friction, NodeColumn{});
  w.pair_d = Eigen::VectorXd::Zero(std::max(1, pairs));
  w.delassus = Eigen::MatrixXd::Zero(std::max(1, 2 * friction), std::max(1, 2 * friction));
  w.friction_p = Eigen::VectorXd::Zero(std::max(1, 2 * friction));
  w.friction_vt = Eigen::VectorXd::Zero(std::max(1, 2 * friction));
  w.friction_bound = Eigen::VectorXd::Zero(std::max(1, friction));
  return w;
}

ThreadState MakeStraightThreadState(const ThreadModel& model, const Eigen::Vector3d& p0_W,
                                    const Eigen::Vector3d& dir_W) {
  const Eigen::Vector3d u = dir_W.normalized();
  Eigen::Matrix3Xd x(3, model.num_nodes);
  double s_m = 0.0;
  for (int i = 0; i < model.num_nodes; ++i) {
    x.col(i) = p0_W + s_m * u;
    if (i < model.num_links) s_m += model.rest_length_m[i];
  }
  return MakeThreadState(model, x);
}

}  // namespace microdex::thread
