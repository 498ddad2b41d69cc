#include "station/device_mapping.h"

#include <cmath>
#include <stdexcept>

namespace microdex::station {

void DeviceMappingDef::Validate() const {
  if (!R_WD.allFinite() || !(R_WD * R_WD.transpose()).isIdentity(1e-9) ||
      !(R_WD.determinant() > 0)) {
    throw std::invalid_argument("R_WD: expected a rotation");
  }
  if (!p_W_centre.allFinite()) throw std::invalid_argument("p_W_centre: expected finite");
  if (!(motion_scale > 0 && motion_scale <= 10)) {
    throw std::invalid_argument("motion_scale: expected 0 < scale <= 10");
  }
  if (!(force_scale >= 0 && force_scale <= 100)) {
    throw std::invalid_argument("force_scale: expected 0..100");
  }
  if (!(max_force_N >= 0 && max_force_N <= 50)) {
    throw std::invalid_argument("max_force_N: expected 0..50 N");
  }
}

DeviceMapping::DeviceMapping(const DeviceMappingDef& def) : def_(def), anchor_W_(def.p_W_centre) {
  def_.Validate();
  X_WT_.translation() = def_.p_W_centre;
}

Eigen::Isometry3d DeviceMapping::Map(const RawDeviceSample& s) {
  const bool clutch = (s.buttons & def_.clutch_button) != 0;
  if (clutch || recentre_) {
    // The tool stays; the hand's position now anchors the tool's.
    anchor_D_ = s.p_D;
    anchor_W_ = X_WT_.translation();
    recentre_ = false;
    clutched_ = clutch;
    if (clutch) return X_WT_;
  }
  clutched_ = false;
  X_WT_.linear() = def_.R_WD * s.q_D.normalized().toRotationMatrix();
  X_WT_.translation() = anchor_W_ + def_.motion_scale * (def_.R_WD * (s.p_D - anchor_D_));
  return X_WT_;
}

Eigen::Vector3d DeviceMapping::ForceToDevice(const Eigen::Vector3d& f_T_W) const {
  Eigen::Vector3d f = def_.force_scale * (def_.R_WD.transpose() * f_T_W);
  if (!f.allFinite()) return Eigen::Vector3d::Zero();
  const double n = f.norm();
  if (n > def_.max_force_N) f *= def_.max_force_N / n;
  return f;
}

}  // namespace microdex::station
