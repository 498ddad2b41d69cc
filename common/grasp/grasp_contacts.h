#pragma once
// Contact generation between the object and the table plane z = 0 and between the object and
// the jaws' inner faces (README.md "Contacts"), analytic and allocation-free.

#include <array>

#include "common/grasp/grasp_model.h"

namespace microdex::grasp {

// The jaws' inner faces for a tool pose and gripper value (JawDef: translating jaws).
std::array<JawFace, 2> CalcJawFaces(const GraspModel& model, const Eigen::Isometry3d& X_WT,
                                    double gripper);
// Half the distance between the jaws' faces for a gripper value in [0, 1].
double CalcHalfGap(const JawDef& jaws, double gripper);

// Stage: clears the contact list (reads nothing else).
void ClearContacts(GraspWorkspace& w);
// Stage: appends the object's support points within the margin of the table (reads the
// object's pose in state; writes w.contacts).
void ContactsFromTable(const GraspModel& model, const GraspState& state, double h,
                       GraspWorkspace& w);
// Stage: appends the contacts of both jaws' inner faces at the end of the sub-step (w.faces1)
// with the object where it is now: its support points over a face, and the face's line
// samples that enter the object. The jaws' material velocities come from their motion over the
// sub-step (w.X_WT0/gripper0 to w.X_WT1/gripper1). Reads state; writes w.contacts.
void ContactsFromJaws(const GraspModel& model, const GraspState& state, double h,
                      GraspWorkspace& w);

}  // namespace microdex::grasp
