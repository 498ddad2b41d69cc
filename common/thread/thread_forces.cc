#include "common/thread/thread_forces.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace microdex::thread {

void AddStretchForces(const ThreadModel& model, const Eigen::Matrix3Xd& x_W, Eigen::Matrix3Xd& f_W,
                      BandedSpd* system, double h2) {
  for (int j = 0; j < model.num_links; ++j) {
    const Eigen::Vector3d e = x_W.col(j + 1) - x_W.col(j);
    const double l = e.norm();
    if (!(l > 0.0)) continue;  // coincident nodes: no direction, no force
    const Eigen::Vector3d u = e / l;
    const double k = model.stretch_k_N_per_m[j];
    const double r = model.rest_length_m[j];
    // (5.4), re-derived: a stretched link pulls N_j towards N_{j+1} and N_{j+1} back.
    const Eigen::Vector3d f = k * (l - r) * u;
    f_W.col(j) += f;
    f_W.col(j + 1) -= f;
    if (system != nullptr) {
      const Eigen::Matrix3d uu = u * u.transpose();
      const double transverse = std::max(0.0, 1.0 - r / l);
      const Eigen::Matrix3d kb = (h2 * k) * (uu + transverse * (Eigen::Matrix3d::Identity() - uu));
      system->AddBlock(j, j, kb);
      system->AddBlock(j + 1, j + 1, kb);
      system->AddBlock(j + 1, j, -kb);
    }
  }
}

double CalcTurningAngle(const Eigen::Matrix3Xd& x_W, int i) {
  const Eigen::Vector3d e1 = x_W.col(i) - x_W.col(i - 1);
  const Eigen::Vector3d e2 = x_W.col(i + 1) - x_W.col(i);
  return std::atan2(e1.cross(e2).norm(), e1.dot(e2));
}

void AddBendForces(const ThreadModel& model, const Eigen::Matrix3Xd& x_W, Eigen::Matrix3Xd& f_W,
                   BandedSpd* system, double h2) {
  for (int i = 1; i + 1 < model.num_nodes; ++i) {
    const double k = model.bend_k_N_m[i];
    const Eigen::Vector3d e1 = x_W.col(i) - x_W.col(i - 1);
    const Eigen::Vector3d e2 = x_W.col(i + 1) - x_W.col(i);
    const double l1 = e1.norm();
    const double l2 = e2.norm();
    if (l1 > 0.0 && l2 > 0.0) {
      const Eigen::Vector3d t1 = e1 / l1;
      const Eigen::Vector3d t2 = e2 / l2;
      const double c = std::clamp(t1.dot(t2), -1.0, 1.0);
      const double sn = t1.cross(t2).norm();
      const double theta = std::atan2(sn, c);
      // theta / sin(theta), finite as theta -> 0; a fully folded joint (theta -> pi) has no
      // defined bend plane and is left to the contact forces.
      double ratio = 1.0;
      if (theta > 1e-4) ratio = sn > 1e-9 ? theta / sn : 0.0;
      // d theta / d e1 = -(t2 - c t1) / (l1 sin), d theta / d e2 = -(t1 - c t2) / (l2 sin);
      // g = theta * d theta / d e, so dE/de = k g and F = -dE/dx (5.5 re-derived; the node's
      // own angle term, missing in the thesis, makes the three forces sum to zero).
      const Eigen::Vector3d g1 = -(ratio / l1) * (t2 - c * t1);
      const Eigen::Vector3d g2 = -(ratio / l2) * (t1 - c * t2);
      const Eigen::Vector3d dE1 = k * g1;
      const Eigen::Vector3d dE2 = k * g2;
      f_W.col(i - 1) += dE1;
      f_W.col(i) -= dE1 - dE2;
      f_W.col(i + 1) -= dE2;
    }
    if (system != nullptr) {
      const double r0 = model.rest_length_m[i - 1];
      const double r1 = model.rest_length_m[i];
      const double c[3] = {1.0 / r0, -(1.0 / r0 + 1.0 / r1), 1.0 / r1};
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b <= a; ++b) {
          system->AddIdentityBlock(i - 1 + a, i - 1 + b, h2 * k * c[a] * c[b]);
        }
      }
    }
  }
}

void CalcTwistTorques(const ThreadModel& model, const Eigen::VectorXd& q_rad,
                      Eigen::VectorXd& tau_N_m) {
  tau_N_m.setZero();
  for (int j = 0; j < model.num_links; ++j) {
    const double tau = model.twist_k_N_m[j] * (q_rad[j + 1] - q_rad[j]);  // (5.6)
    tau_N_m[j] += tau;
    tau_N_m[j + 1] -= tau;
  }
}

void AddTwistCouplingForces(const ThreadModel& model, const Eigen::Matrix3Xd& x_W,
                            const Eigen::VectorXd& q_rad, Eigen::Matrix3Xd& f_W) {
  const double kt = model.def.twist_coupling_N;
  if (kt == 0.0) return;
  for (int j = 1; j + 1 < model.num_nodes; ++j) {
    const Eigen::Vector3d e1 = x_W.col(j) - x_W.col(j - 1);
    const Eigen::Vector3d e2 = x_W.col(j + 1) - x_W.col(j);
    const double l1 = e1.norm();
    const double l2 = e2.norm();
    if (!(l1 > 0.0 && l2 > 0.0)) continue;
    const double twist = q_rad[j] - q_rad[j - 1];
    const Eigen::Vector3d f = (kt * twist / (l1 * l2)) * e1.cross(e2);  // (5.7)
    f_W.col(j + 1) += f;
    f_W.col(j) -= f;
  }
}

void AddGravityForces(const ThreadModel& model, Eigen::Matrix3Xd& f_W) {
  for (int i = 0; i < model.num_nodes; ++i) {
    f_W.col(i) += model.mass_kg[i] * model.def.gravity_m_per_s2;
  }
}

double CalcStretchEnergy(const ThreadModel& model, const Eigen::Matrix3Xd& x_W) {
  double e = 0.0;
  for (int j = 0; j < model.num_links; ++j) {
    const double d = (x_W.col(j + 1) - x_W.col(j)).norm() - model.rest_length_m[j];
    e += 0.5 * model.stretch_k_N_per_m[j] * d * d;
  }
  return e;
}

double CalcBendEnergy(const ThreadModel& model, const Eigen::Matrix3Xd& x_W) {
  double e = 0.0;
  for (int i = 1; i + 1 < model.num_nodes; ++i) {
    const double theta = CalcTurningAngle(x_W, i);
    e += 0.5 * model.bend_k_N_m[i] * theta * theta;
  }
  return e;
}

double CalcTwistEnergy(const ThreadModel& model, const Eigen::VectorXd& q_rad) {
  double e = 0.0;
  for (int j = 0; j < model.num_links; ++j) {
    const double d = q_rad[j + 1] - q_rad[j];
    e += 0.5 * model.twist_k_N_m[j] * d * d;
  }
  return e;
}

double CalcKineticEnergy(const ThreadModel& model, const ThreadState& state) {
  double e = 0.0;
  for (int i = 0; i < model.num_nodes; ++i) {
    e += 0.5 * model.mass_kg[i] * state.v_W.col(i).squaredNorm();
    e += 0.5 * model.inertia_kg_m2[i] * state.qdot_rad_per_s[i] * state.qdot_rad_per_s[i];
  }
  return e;
}

double CalcMaxStrain(const ThreadModel& model, const Eigen::Matrix3Xd& x_W) {
  double worst = 0.0;
  for (int j = 0; j < model.num_links; ++j) {
    const double r = model.rest_length_m[j];
    const double strain = std::abs((x_W.col(j + 1) - x_W.col(j)).norm() - r) / r;
    if (!(strain <= worst)) worst = strain;  // NaN propagates as the worst
  }
  return worst;
}

}  // namespace microdex::thread
