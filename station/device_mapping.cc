#include "station/device_mapping.h"

#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "common/base/yaml_reader.h"

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
  if (!(torque_scale >= 0 && torque_scale <= 100)) {
    throw std::invalid_argument("torque_scale: expected 0..100");
  }
  if (!(max_torque_Nm >= 0 && max_torque_Nm <= 5)) {
    throw std::invalid_argument("max_torque_Nm: expected 0..5 N m");
  }
}

namespace {

constexpr std::string_view kMappingKeys[] = {"rpy_rad",      "motion_scale", "force_scale",
                                             "max_force_N",  "torque_scale", "max_torque_Nm",
                                             "clutch_button"};

DeviceMappingDef ReadMapping(const YamlSection& y, const DeviceMappingDef& defaults) {
  DeviceMappingDef d = defaults;
  if (y.Has("rpy_rad")) {
    const Eigen::Vector3d rpy = y.Vec3("rpy_rad", Eigen::Vector3d::Zero());
    if (!rpy.allFinite()) y.FailInvalid(std::invalid_argument("rpy_rad: expected finite angles"));
    d.R_WD = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
              Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
              Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                 .toRotationMatrix();
  }
  d.motion_scale = y.FiniteDouble("motion_scale", d.motion_scale);
  d.force_scale = y.FiniteDouble("force_scale", d.force_scale);
  d.max_force_N = y.FiniteDouble("max_force_N", d.max_force_N);
  d.torque_scale = y.FiniteDouble("torque_scale", d.torque_scale);
  d.max_torque_Nm = y.FiniteDouble("max_torque_Nm", d.max_torque_Nm);
  if (y.Has("clutch_button")) {
    const int bit = y.Int("clutch_button", 7);
    if (bit < 0 || bit > 31) {
      y.FailInvalid(std::invalid_argument("clutch_button: expected a bit index 0..31"));
    }
    d.clutch_button = 1u << bit;
  }
  try {
    d.Validate();
  } catch (const std::invalid_argument& e) {
    y.FailInvalid(e);
  }
  return d;
}

}  // namespace

DeviceMappingDef LoadDeviceMapping(const std::string& path, int device,
                                   const DeviceMappingDef& defaults) {
  const YamlSection root = YamlReader(path).Root();
  std::vector<std::string_view> keys(std::begin(kMappingKeys), std::end(kMappingKeys));
  keys.push_back("second");
  root.CheckNoUnknownKeys(keys);
  if (device == 0) return ReadMapping(root, defaults);
  const std::optional<YamlSection> second = root.OptionalMap("second");
  if (!second) return defaults;
  second->CheckNoUnknownKeys(kMappingKeys);
  return ReadMapping(*second, defaults);
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

Eigen::Vector3d DeviceMapping::TorqueToDevice(const Eigen::Vector3d& tau_T_W) const {
  Eigen::Vector3d tau = def_.torque_scale * (def_.R_WD.transpose() * tau_T_W);
  if (!tau.allFinite()) return Eigen::Vector3d::Zero();
  const double n = tau.norm();
  if (n > def_.max_torque_Nm) tau *= def_.max_torque_Nm / n;
  return tau;
}

}  // namespace microdex::station
