#pragma once
// Description of the grasping primitive (thesis §2.2, Fig. 2.2d: forceps closing on a small
// object that rotates or slips out when the jaws align poorly with it), in SI units, with its one
// validation point. README.md describes the model.

#include <Eigen/Core>

namespace microdex::grasp {

enum class ShapeKind {
  kBox,       // box_size_m: full edge lengths along the object's x, y, z axes
  kCylinder,  // radius_m and length_m, axis along the object's z axis
  kSphere,    // radius_m
};

const char* ShapeKindName(ShapeKind kind);

// The object's collision and mass geometry, in its body frame O (origin at the centre of mass,
// axes along the principal axes of inertia).
struct ShapeDef {
  ShapeKind kind = ShapeKind::kBox;
  Eigen::Vector3d box_size_m = Eigen::Vector3d(1e-3, 1e-3, 1e-3);
  double radius_m = 0.5e-3;
  double length_m = 1e-3;
};

// The forceps' two jaws, translating symmetrically along the tool frame's closing axis y_T. In
// the tool frame T, jaw + has its inner face at y = +half_gap and jaw - at y = -half_gap, both
// faces centred on the y axis, spanning x in [-width/2, width/2] (across the jaw) and
// z in [-length/2, length/2] (along the forceps' shaft, which points to +z_T), each face normal
// pointing into the gap. half_gap = (1 - g) open_gap_m / 2 + g closed_gap_m / 2 for the gripper
// value g in [0, 1] (1 closed). closed_gap_m may be negative: the jaws then squeeze through
// each other's plane, which is how a trainee presses harder on an object held between them.
struct JawDef {
  double width_m = 1e-3;
  double length_m = 3e-3;
  double thickness_m = 0.3e-3;
  double open_gap_m = 4e-3;
  double closed_gap_m = -0.5e-3;
};

// Compliant contact (README.md "Solver"): each contact pair (object–table, object–jaw +,
// object–jaw -) is a spring of the given stiffness, shared equally among the pair's contact
// points, with a damping given as a ratio of the critical damping of the object's mass on that
// spring. The spring and damper are integrated implicitly, so any stiffness is stable.
struct ContactDef {
  double table_stiffness_N_per_m = 1e4;
  double jaw_stiffness_N_per_m = 1e4;
  double damping_ratio = 1.0;
  // Points closer than this (plus the distance the object moves in a step) become speculative
  // contacts, so a fast object cannot pass through a face between two steps.
  double speculative_margin_m = 20e-6;
  // A contact point's spring is at most this times m_eff / h^2 (m_eff its effective mass, h the
  // sub-step): the stiffest spring the step resolves for that mass (README.md "Solver"). The
  // jaws squeeze from both sides and need the tighter limit; the table's sets its sag under
  // the weight, at most g h^2 / limit.
  double jaw_stiffness_limit = 1.0;
  double table_stiffness_limit = 10.0;
};

// The contact solver: projected Gauss–Seidel on the normal and friction impulses, warm started.
struct SolverDef {
  int iterations = 20;
  int substeps = 1;
};

// Thresholds of the trainer's metrics (README.md "Metrics").
struct MetricsDef {
  // A jaw grips when its normal force exceeds this fraction of the object's weight m |gravity|.
  double grip_weight_fraction = 1e-3;
  // A grasp (the span over which induced rotation is measured) ends after the jaws have not
  // touched the object for this long.
  double release_time_s = 0.05;
};

struct GraspDef {
  ShapeDef shape;
  double density_kg_per_m3 = 1000.0;
  // Coulomb friction coefficient, object on jaws and object on table.
  double jaw_friction = 0.5;
  double table_friction = 0.5;
  JawDef jaws;
  ContactDef contact;
  SolverDef solver;
  MetricsDef metrics;
  Eigen::Vector3d gravity_m_per_s2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  // Largest time step StepGrasp accepts (a larger one is counted as an invalid input).
  double max_time_step_s = 0.01;

  // Throws std::invalid_argument for the first bad field; the message starts with the field
  // name followed by ': ' (e.g. `shape.radius_m: expected a radius in [1e-5, 0.05] m`).
  void Validate() const;
};

}  // namespace microdex::grasp
