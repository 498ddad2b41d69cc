#pragma once
// Scenes of the grasp tests and of `microdex-bench grasp`: a box on a tilted table, and
// forceps that close on an object, lift it and hold it.

#include <Eigen/Core>
#include <vector>

#include "common/grasp/grasp_model.h"

namespace microdex::grasp::testing {

// A 1 mm cube of density 1000 kg/m^3 (1 mg), jaws with 0.8 mm x 0.8 mm faces opening to 2 mm,
// soft jaws (1 N/m) so that the grip forces of a milligram are squeezes of micrometres.
GraspDef MilligramCubeDef(double jaw_friction = 0.5);

// A tool far from the scene (no jaw contact).
GraspInput FarTool(double dt_s = 1e-3);

// A box on a table tilted by theta_rad (gravity tilted towards +x), released at rest.
struct InclineResult {
  double acceleration_m_per_s2 = 0.0;  // along the slope, mean over [t0, t1]
  double displacement_m = 0.0;         // along the slope over [t0, t1]
  bool finite = true;
};
InclineResult RunIncline(GraspDef def, double theta_rad, double t0_s, double t1_s);

// Forceps close on the object on the table, squeeze it, lift it and hold it.
struct LiftOptions {
  double squeeze_m = 10e-6;  // the jaws' gap at the end of closing: object width - 2 squeeze
  double offset_x_m = 0.0;   // closing line offset from the centre of mass along world x
  double yaw_rad = 0.0;      // the jaws' rotation about world z against the object's faces
  double lift_m = 0.5e-3;    // how far the tool rises
  double close_s = 0.2, settle_s = 0.1, lift_s = 0.5, hold_s = 0.5;
  double dt_s = 1e-3;
};
struct LiftResult {
  double grip_force_N = 0.0;    // metrics.grip_force_N at the end of settling
  double rise_m = 0.0;          // the object's centre of mass, end minus start
  bool lifted = false;          // rose by more than half the lift and held off the table
  double rotation_y_rad = 0.0;  // signed rotation about world y at the end (misaligned grasp)
  double yaw_rad = 0.0;         // signed rotation about world z at the end
  GraspState final;
};
// The object's width along the closing direction must be given (the jaws' gap is set from it).
// step_us, when given, receives the wall time of every StepGrasp call in microseconds.
LiftResult RunLift(const GraspDef& def, double width_m, const LiftOptions& options,
                   std::vector<double>* step_us = nullptr);

// The smallest grip force that lifts the object, by bisection on the squeeze: the grip forces
// of the last squeeze that dropped it and the first that lifted it.
struct HoldThreshold {
  double dropped_grip_N = 0.0;
  double held_grip_N = 0.0;
  double threshold_N() const { return 0.5 * (dropped_grip_N + held_grip_N); }
};
HoldThreshold FindHoldThreshold(const GraspDef& def, double width_m, int bisections);

}  // namespace microdex::grasp::testing
