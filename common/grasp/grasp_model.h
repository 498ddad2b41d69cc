#pragma once
// The grasping primitive's model (built once from a GraspDef), its device input, its plain
// copyable state and the step's workspace (README.md "Model").

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "common/grasp/grasp_def.h"
#include "common/grasp/grasp_shape.h"

namespace microdex::grasp {

// Contact pairs, the index of a contact's pair.
enum ContactPair : int { kTablePair = 0, kJawPlusPair = 1, kJawMinusPair = 2, kNumPairs = 3 };

// Capacity of the contact list. The candidates per jaw are the object's support points, the 9
// line samples of the face and the two clipped ends of each support edge (grasp_contacts.cc),
// and on the table the support points; of those only the ones near the face count, which for
// the shapes here stays below this bound (an overflow is counted in the warnings).
inline constexpr int kJawLineSamples = 9;
inline constexpr int kMaxContacts = 64;
// Contact keys: pair * kKeysPerPair + feature (support point, then line sample, then clipped
// edge end).
inline constexpr int kKeysPerPair = 64;

struct GraspModel {
  GraspDef def;  // validated
  ShapeGeometry shape;
  double mass_kg = 0.0;
  Eigen::Vector3d inertia_kg_m2 = Eigen::Vector3d::Zero();  // principal, about O
  Eigen::Vector3d inv_inertia_per_kg_m2 = Eigen::Vector3d::Zero();
  double weight_N = 0.0;  // m |gravity|
  // Per pair (ContactPair): spring stiffness N/m and damper N s/m of the whole pair.
  std::array<double, kNumPairs> stiffness_N_per_m{};
  std::array<double, kNumPairs> damping_N_s_per_m{};
  std::array<double, kNumPairs> friction{};
};

// Builds the model; throws std::invalid_argument (from GraspDef::Validate) on a bad def.
GraspModel MakeGraspModel(const GraspDef& def);

// One device sample: the tool pose, the gripper value and the step length.
struct GraspInput {
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();
  double gripper = 0.0;  // [0, 1], 1 closed; clamped
  double dt_s = 1e-3;
};

// A rigid pose that compares exactly (Eigen's quaternion has no operator==).
struct Pose {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Vector4d q_xyzw = Eigen::Vector4d(0.0, 0.0, 0.0, 1.0);  // unit quaternion
  Eigen::Quaterniond q() const {
    return Eigen::Quaterniond(q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]);
  }
  void set_q(const Eigen::Quaterniond& q) { q_xyzw = Eigen::Vector4d(q.x(), q.y(), q.z(), q.w()); }
  bool operator==(const Pose&) const = default;
};

// A contact's accumulated impulse, kept for the next step's warm start. key identifies the
// contact across steps (kKeysPerPair); -1: unused.
struct ContactImpulse {
  int key = -1;
  double normal_N_s = 0.0;
  Eigen::Vector3d friction_N_s_W = Eigen::Vector3d::Zero();
  bool operator==(const ContactImpulse&) const = default;
};

// The trainer's metrics, accumulated by UpdateMetrics (README.md "Metrics").
struct GraspMetrics {
  bool grasping = false;  // the jaws have touched the object within release_time_s
  bool held = false;      // both jaws press on it
  bool lifted = false;    // held and off the table
  double time_since_jaw_contact_s = 0.0;
  Pose touch_pose;                        // the object's pose when the jaws first touched it
  double induced_rotation_rad = 0.0;      // rotation since the first touch of the current grasp
  double max_induced_rotation_rad = 0.0;  // over every grasp
  double alignment_angle_rad = 0.0;       // at the first touch: closing direction to face normal
  double closing_offset_m = 0.0;          // at the first touch: closing line to centre of mass
  double grip_force_N = 0.0;              // last step: mean normal force of the two jaws
  double peak_grip_force_N = 0.0;
  double held_time_s = 0.0;
  double grip_impulse_held_N_s = 0.0;  // integral of the grip force while held
  double slip_distance_m = 0.0;        // relative sliding at the jaws while held
  int grasps = 0;                      // first touches
  int lifts = 0;
  int drops = 0;
  double mean_grip_force_N() const {
    return held_time_s > 0.0 ? grip_impulse_held_N_s / held_time_s : 0.0;
  }
  bool operator==(const GraspMetrics&) const = default;
};

// Numerical trouble and capacity events, counted, never thrown (README.md "Warnings").
struct GraspWarnings {
  std::int64_t invalid_inputs = 0;    // NaN/Inf pose or gripper (jaws held still), bad dt (skipped)
  std::int64_t nonfinite_resets = 0;  // the step produced NaN/Inf: object put back at rest
  std::int64_t contact_overflows = 0;  // more candidate contacts than kMaxContacts
  bool operator==(const GraspWarnings&) const = default;
};

// What the haptic loop reads after a step.
struct GraspOutput {
  // Force and torque (about the tool origin T) of the object on the forceps, world frame; the
  // mean over the last step.
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d tau_T_W = Eigen::Vector3d::Zero();
  std::array<double, kNumPairs> normal_force_N{};  // per pair, mean over the step
  double max_penetration_m = 0.0;                  // deepest contact after the step
  int num_contacts = 0;                            // in the last sub-step
  bool operator==(const GraspOutput&) const = default;
};

// Everything that determines the future, and nothing else: a plain copyable value.
struct GraspState {
  double time_s = 0.0;
  std::int64_t steps = 0;
  Pose X_WO;                                            // the object's centre of mass and axes
  Eigen::Vector3d v_WO = Eigen::Vector3d::Zero();       // velocity of O, world
  Eigen::Vector3d w_WO = Eigen::Vector3d::Zero();       // angular velocity, world
  Pose X_WT;                                            // the tool at the end of the last step
  double gripper = 0.0;                                 // at the end of the last step
  bool has_tool = false;                                // false before the first valid input
  std::array<ContactImpulse, kMaxContacts> impulses{};  // warm start
  GraspOutput out;
  GraspMetrics metrics;
  GraspWarnings warnings;
  bool operator==(const GraspState&) const = default;
};

// A contact of the current sub-step (workspace only).
struct Contact {
  int pair = kTablePair;
  int key = -1;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();        // on the object's surface
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();       // unit, pushes the object
  double separation_m = 0.0;                            // < 0: penetration
  Eigen::Vector3d v_other_W = Eigen::Vector3d::Zero();  // velocity of the other body's point
  // Solver data (SolveContacts).
  Eigen::Vector3d r_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d t1_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d t2_W = Eigen::Vector3d::Zero();
  double normal_mass_kg = 0.0;
  Eigen::Matrix2d tangent_mass_kg = Eigen::Matrix2d::Zero();
  double slide_mass_kg = 0.0;
  double softness = 0.0;  // m/(N s) per N s
  double bias_m_per_s = 0.0;
  double normal_N_s = 0.0;
  Eigen::Vector2d friction_N_s = Eigen::Vector2d::Zero();
};

// The jaws' faces in world: centre, normal into the gap and in-face axes (x_T, z_T).
struct JawFace {
  Eigen::Vector3d c_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitY();
  Eigen::Vector3d u_W = Eigen::Vector3d::UnitX();
  Eigen::Vector3d w_W = Eigen::Vector3d::UnitZ();
};

// Caches of a step, fixed size; nothing in it carries over from one step to the next.
struct GraspWorkspace {
  std::array<Contact, kMaxContacts> contacts{};
  int num_contacts = 0;
  int overflows = 0;  // contacts that did not fit, this step
  // The tool at the start and end of the current sub-step, and its gripper value.
  Eigen::Isometry3d X_WT0 = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d X_WT1 = Eigen::Isometry3d::Identity();
  double gripper0 = 0.0;
  double gripper1 = 0.0;
  std::array<JawFace, 2> faces0{};                  // start of the sub-step
  std::array<JawFace, 2> faces1{};                  // end of the sub-step
  std::array<ContactImpulse, kMaxContacts> warm{};  // the last sub-step's impulses
  // Sums over the step's sub-steps.
  std::array<double, kNumPairs> normal_impulse_N_s{};
  Eigen::Vector3d f_impulse_T_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d tau_impulse_T_W = Eigen::Vector3d::Zero();
  double slip_m = 0.0;
  Pose X_WO_start;  // the object at the start of the step
};

// An object of the model at rest on the table (lowest point at z = 0), centre of mass above
// p_W's x, y, with orientation q_WO; no tool yet.
GraspState MakeGraspStateOnTable(const GraspModel& model, const Eigen::Vector3d& p_W,
                                 const Eigen::Quaterniond& q_WO = Eigen::Quaterniond::Identity());
// Lowest point of the object with pose (p, q) above z = 0 (negative when below).
double CalcLowestPoint(const GraspModel& model, const Eigen::Vector3d& p_WO,
                       const Eigen::Quaterniond& q_WO);

}  // namespace microdex::grasp
