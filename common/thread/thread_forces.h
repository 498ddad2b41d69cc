#pragma once
// Internal forces of the thread (thesis §5.2), re-derived from energies so that each force is
// the exact negative gradient of its energy and conserves linear momentum, and the stiffness
// bounds the linearly implicit step needs.

#include <Eigen/Core>

#include "common/thread/banded_spd.h"
#include "common/thread/thread_model.h"

namespace microdex::thread {

// Stretch/compression (5.4): E = 1/2 kappa_s (l - r)^2 per link. Adds the forces to f_W; when
// system is given, adds h2 times the stiffness k [u u^T + max(0, 1 - r/l)(I - u u^T)] (the
// spring Hessian with its indefinite part clipped, so the system stays SPD).
void AddStretchForces(const ThreadModel& model, const Eigen::Matrix3Xd& x_W, Eigen::Matrix3Xd& f_W,
                      BandedSpd* system, double h2);

// Bending (5.5): E = 1/2 kappa_b theta^2 per interior node, theta the turning angle between
// successive links (theta = pi - alpha of the thesis). When system is given, adds h2 times the
// constant small-angle stiffness kappa_b c c^T (x) I with c = (1/r0, -(1/r0 + 1/r1), 1/r1).
void AddBendForces(const ThreadModel& model, const Eigen::Matrix3Xd& x_W, Eigen::Matrix3Xd& f_W,
                   BandedSpd* system, double h2);

// Torsion torque (5.6): tau_i = kappa_d,i (q_{i+1} - q_i) - kappa_d,i-1 (q_i - q_{i-1}).
void CalcTwistTorques(const ThreadModel& model, const Eigen::VectorXd& q_rad,
                      Eigen::VectorXd& tau_N_m);

// Twist-to-bend coupling (5.7): at a bend of node j, the twist of the link before it pushes
// node j + 1 out of the bend plane with kappa_t * twist * (u_{j-1} x u_j) (unit link vectors,
// so the cross product carries sin(theta)); node j takes the opposite force.
void AddTwistCouplingForces(const ThreadModel& model, const Eigen::Matrix3Xd& x_W,
                            const Eigen::VectorXd& q_rad, Eigen::Matrix3Xd& f_W);

void AddGravityForces(const ThreadModel& model, Eigen::Matrix3Xd& f_W);

// Energies, for tests and the stability study.
double CalcStretchEnergy(const ThreadModel& model, const Eigen::Matrix3Xd& x_W);
double CalcBendEnergy(const ThreadModel& model, const Eigen::Matrix3Xd& x_W);
double CalcTwistEnergy(const ThreadModel& model, const Eigen::VectorXd& q_rad);
double CalcKineticEnergy(const ThreadModel& model, const ThreadState& state);
// Largest |l - r| / r over links.
double CalcMaxStrain(const ThreadModel& model, const Eigen::Matrix3Xd& x_W);
// Turning angle at interior node i, in [0, pi].
double CalcTurningAngle(const Eigen::Matrix3Xd& x_W, int i);

}  // namespace microdex::thread
