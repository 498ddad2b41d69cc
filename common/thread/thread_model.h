#pragma once
// The suture thread's model (built once from a ThreadDef) and its plain, copyable state
// (thesis §5.2, Fig. 5.1): nodes N_0..N_k with position x_i, velocity, torsion angle q_i and its
// rate; links L_i between N_i and N_{i+1} (0-based) with rest lengths.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "common/thread/banded_spd.h"
#include "common/thread/sphere_bvh.h"
#include "common/thread/strain_band.h"
#include "common/thread/thread_def.h"

namespace microdex::thread {

struct ThreadModel {
  ThreadDef def;  // validated
  int num_nodes = 0;
  int num_links = 0;
  double radius_m = 0.0;
  Eigen::VectorXd rest_length_m;      // per link
  Eigen::VectorXd stretch_k_N_per_m;  // per link, kappa_s (5.4)
  Eigen::VectorXd bend_k_N_m;         // per node (ends unused), kappa_b (5.5)
  Eigen::VectorXd twist_k_N_m;        // per link, kappa_d (5.6)
  Eigen::VectorXd mass_kg;            // per node, m_i (5.1)
  Eigen::VectorXd inertia_kg_m2;      // per node, I_i (5.1): (1/2) m r^2 of a solid cylinder
  Eigen::VectorXd drag_N_s_per_m;     // per node, kappa_fx (5.8)
  SphereBvhTopology bvh;
  // Leaf spheres grow by this: thread radius plus contact cutoff plus a motion margin, so
  // pairs that may touch before the next step are already candidates.
  double bvh_inflate_m = 0.0;
  int contact_capacity = 0;        // self pairs and object contacts, each
  int half_bandwidth = 8;          // of the 3N x 3N implicit matrix
  int exact_pair_capacity = 0;     // self contacts coupled exactly in the implicit step
  int friction_capacity = 0;       // contacts with friction per step
  int friction_self_capacity = 0;  // of those, self contacts at most
};

// Builds the model; throws std::invalid_argument (from ThreadDef::Validate) on a bad def.
ThreadModel MakeThreadModel(const ThreadDef& def);

// A grasped control node (thesis §5.4): it follows the tool tip p_WT and the tool's roll.
struct Grasp {
  int node = -1;  // -1: free slot
  Eigen::Vector3d p_WT = Eigen::Vector3d::Zero();
  double roll_rad = 0.0;
  // Force the thread exerts on the tool (what a haptic device renders), world frame, N.
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();
};

// Link–link contact (5.9): links a < b, closest points at parameters s, t.
struct SelfContact {
  int link_a = 0;
  int link_b = 0;
  double s = 0.0;
  double t = 0.0;
  double gap_m = 0.0;
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();  // unit, from link b to link a
};

// A self contact's normal force carried from one step to the next while a knot is held
// (ThreadState::carry_contact_forces; README, "Carried contact forces in a held knot"),
// found again by its pair of links.
struct CarriedContact {
  int link_a = -1;
  int link_b = -1;
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();  // the contact's normal when it was stored
  double force_N = 0.0;
};
inline constexpr int kMaxCarriedContacts = 16;

// A candidate pair's closest points at the start of the step (ProjectContacts).
struct PairStart {
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();
  double distance_m = 0.0;
  bool interior = false;
};

// Link–object contact (5.9): the object pushes along n_W.
struct ObjectContact {
  int link = 0;
  int collider = 0;
  double s = 0.0;
  double gap_m = 0.0;
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();
};

// Counters of numerical trouble and of the last step's work (never thrown; published).
struct ThreadStatus {
  std::int64_t steps = 0;
  std::int64_t nonfinite_resets = 0;        // a step produced NaN/Inf: state rolled back
  std::int64_t factorization_failures = 0;  // non-SPD system: state rolled back
  std::int64_t contact_overflows = 0;       // more candidate pairs than capacity
  std::int64_t guard_corrections = 0;       // non-penetration projections applied
  std::int64_t strain_corrections = 0;      // link lengths projected by the strain limit
  std::int64_t pair_tests = 0;  // link-pair distances computed by the contact projection
  int num_candidate_pairs = 0;
  int num_self_contacts = 0;
  int num_object_contacts = 0;
  int num_exact_pairs = 0;        // self contacts coupled exactly in the last implicit step
  int num_bound_pairs = 0;        // self contacts beyond exact_pair_capacity: diagonal bound
  int num_friction_contacts = 0;  // contacts with friction in the last step
  int num_sliding_contacts = 0;   // of those, at the friction cone's limit (slipping)
  double max_strain = 0.0;        // max |l - r| / r after the step
};

// The step's caches and work arrays (contact lists, the sphere BVH's spheres, the banded
// system and its factor, the low-rank terms, the per-node grasp-slot map), sized once by
// MakeThreadWorkspace; no step resizes them. Nothing in it carries over from one step to the
// next: a state stepped with a fresh workspace continues exactly as with a warm one.
struct ThreadWorkspace {
  Eigen::Matrix3Xd f_W;       // force per node
  Eigen::Matrix3Xd x_prev_W;  // state at the start of the step, for rollback
  // Swept contact projection (StepThreadWith): the pairs that may meet during the step, the
  // implicit step's end positions and the start of the current part of the step.
  std::vector<LinkPair> swept_pairs;
  Eigen::Matrix3Xd x_end_W;
  Eigen::Matrix3Xd x_part_W;
  Eigen::Matrix3Xd v_prev_W;
  Eigen::VectorXd q_prev_rad;
  Eigen::VectorXd qdot_prev_rad_per_s;
  Eigen::VectorXd tau_N_m;                             // torsion torque per node
  Eigen::Matrix<double, 9, Eigen::Dynamic> k_contact;  // per node 3x3 contact stiffness bound
  Eigen::VectorXd c_contact_N_s_per_m;                 // per node extra contact damping
  Eigen::VectorXi grasp_slot;  // per node: grasp slot or -1 (from state.grasps, each step)
  SphereBvhSpheres spheres;
  std::vector<LinkPair> pairs;
  // Per candidate pair, from the start-of-step positions (contact projection): the closest
  // points' normal (from b to a) and whether both closest points were interior to their links.
  std::vector<PairStart> pair_start;
  // (link, collider) pairs the contact projection's first sweep found near (within a diameter
  // of their constraint): the only object constraints its later sweeps visit.
  std::vector<LinkPair> object_candidates;
  // The last step's contact projection: sweeps run (the most in one part, and the sum over its
  // parts), and its largest remaining deficit (m).
  int projection_sweeps = 0;
  int projection_sweeps_total = 0;
  double projection_residual_m = 0.0;
  int projection_parts = 0;  // the step's motion was projected in this many parts
  // The contact projection's bookkeeping of what changed: per node the moment (a count of the
  // projection's pair tests) it last moved, per candidate pair the moment it was last found
  // satisfied; a pair satisfied after its nodes' last moves is not tested again.
  Eigen::VectorXi node_moved_at;
  Eigen::VectorXi pair_checked_at;
  Eigen::VectorXi object_checked_at;  // the same per (link, collider) candidate
  // Per node the distance it has moved in the projection so far; per candidate pair found
  // satisfied, its clearance beyond the contact distance plus its nodes' travel at that test
  // (-inf if none): while its nodes' travel stays below that, the pair cannot have closed in.
  Eigen::VectorXd node_travel_m;
  Eigen::VectorXd pair_clear_m;
  // The contact projection's link-length solve (strain band): inverse node masses (0 for
  // grasped nodes) and the tridiagonal solve's scratch.
  Eigen::VectorXd inverse_mass;
  StrainBandScratch strain_band;
  std::vector<SelfContact> self_contacts;
  std::vector<ObjectContact> object_contacts;
  int num_self_contacts = 0;
  int num_object_contacts = 0;
  // Carried forces: the force each of the first num_self_carried self contacts takes from the
  // state's list this step, and the list the step hands on (committed when the step succeeds).
  std::array<double, kMaxCarriedContacts> self_carried_N{};
  int num_self_carried = 0;
  std::array<CarriedContact, kMaxCarriedContacts> carried_next{};
  int num_carried_next = 0;
  BandedSpd system;        // 3N x 3N, half bandwidth 8
  BandedSpd twist_system;  // N x N, tridiagonal
  Eigen::VectorXd rhs;
  Eigen::VectorXd twist_rhs;
  Eigen::MatrixXd
      grasp_rows;  // (3 max_grasps) x (2 p + 2): unmodified rows and rhs of grasped nodes
  // Low-rank contact terms of the implicit step (thread_step.cc): exactly coupled pairs (first
  // exact_pair_capacity columns at most) and two friction columns per friction contact, with
  // grasped nodes' weights zeroed for the solve; the friction columns with all weights (for
  // relative velocities and the tool's reaction); pair weights, the friction Delassus
  // operator, impulses, relative tangential velocities and impulse bounds.
  LowRankSolver low_rank;
  std::vector<NodeColumn> columns;
  std::vector<NodeColumn> friction_columns;
  Eigen::VectorXd pair_d;
  Eigen::MatrixXd delassus;
  Eigen::VectorXd friction_p;
  Eigen::VectorXd friction_vt;
  Eigen::VectorXd friction_bound;
};

// Everything of the thread that determines its future, and nothing else (the workspace holds
// the rest): a plain copyable value.
struct ThreadState {
  double time_s = 0.0;
  Eigen::Matrix3Xd x_W;            // node positions
  Eigen::Matrix3Xd v_W;            // node velocities
  Eigen::VectorXd q_rad;           // torsion angles q_i
  Eigen::VectorXd qdot_rad_per_s;  // torsion rates
  std::vector<Grasp> grasps;       // max_grasps slots
  // While set (a knot held still: KnotHoldScript sets it, KnotThrowScript clears it), the
  // deepest self contacts keep a normal force from step to step, updated from the gap each
  // step's implicit motion reaches (README, "Carried contact forces in a held knot").
  bool carry_contact_forces = false;
  int num_carried = 0;
  std::array<CarriedContact, kMaxCarriedContacts> carried{};
  ThreadStatus status;
};

// The workspace of a model's step, sized once.
ThreadWorkspace MakeThreadWorkspace(const ThreadModel& model);

// A state at rest with the nodes at the given positions (3 x num_nodes), no grasp.
ThreadState MakeThreadState(const ThreadModel& model, const Eigen::Matrix3Xd& x_W);
// A straight thread at rest from p0_W along dir_W, links at their rest length.
ThreadState MakeStraightThreadState(const ThreadModel& model, const Eigen::Vector3d& p0_W,
                                    const Eigen::Vector3d& dir_W);

}  // namespace microdex::thread
