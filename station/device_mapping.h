#pragma once
// From the hand to the tool and back: the workspace mapping of an external device (a rotation
// and a centre), motion scaling for the microscope (the tool moves motion_scale × the hand:
// 0.1 under 10× magnification), a clutch (while the clutch button is held the tool stays
// where it is and the hand moves freely; on release the tool continues from there: re-centring
// the hand without moving the tool), and the force sent back: rotated into the device frame,
// scaled by force_scale and limited to max_force_N.
//
// The mapping is part of the device, not of the simulation: the station records and mirrors
// the mapped (world) pose, so a replay does not need it.
//
// Plain state, no allocation: runs on the haptic thread.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>

#include "station/device_guard.h"

namespace microdex::station {

struct DeviceMappingDef {
  Eigen::Matrix3d R_WD = Eigen::Matrix3d::Identity();    // device axes in world
  Eigen::Vector3d p_W_centre = Eigen::Vector3d::Zero();  // where the device's origin maps
  double motion_scale = 0.1;                             // world metres per hand metre
  double force_scale = 1.0;                              // device newtons per world newton
  double max_force_N = 3.0;                              // the device's own limit
  // Rotations map one to one (the tool turns as the hand), so a torque about the tool point
  // goes to the handle only rotated and scaled by torque_scale, then limited to the device's
  // max_torque_Nm (0: the device renders no torque, e.g. a 3-DOF Touch or Falcon).
  double torque_scale = 1.0;
  double max_torque_Nm = 0.5;
  std::uint32_t clutch_button = 1u << 7;
  // Throws std::invalid_argument("field: reason").
  void Validate() const;
};

// A device's mapping from a YAML file (`microdex-station --device-map FILE`, station/README.md):
// the keys of DeviceMappingDef (rpy_rad for R_WD, motion_scale, force_scale, max_force_N,
// torque_scale, max_torque_Nm, clutch_button as a bit index) at the top level for the first
// device and under `second:` for the second device of a bimanual scene; what a file leaves out
// keeps `defaults`. device: 0 first, 1 second. Throws InputError "FILE:LINE: field: reason".
DeviceMappingDef LoadDeviceMapping(const std::string& path, int device,
                                   const DeviceMappingDef& defaults);

class DeviceMapping {
 public:
  explicit DeviceMapping(const DeviceMappingDef& def = {});
  // The tool pose in world for a hand sample (the clutch read from its buttons).
  Eigen::Isometry3d Map(const RawDeviceSample& s);
  // Re-centre: the next sample continues from the current tool pose (a clutch press and
  // release in one step; used when a device fault ends).
  void Recentre() { recentre_ = true; }
  // The force for the device: rotated into its frame, scaled, limited (finite in, finite out).
  Eigen::Vector3d ForceToDevice(const Eigen::Vector3d& f_T_W) const;
  // The same for a torque about the tool point.
  Eigen::Vector3d TorqueToDevice(const Eigen::Vector3d& tau_T_W) const;
  bool clutched() const { return clutched_; }

 private:
  DeviceMappingDef def_;
  Eigen::Vector3d anchor_D_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d anchor_W_;
  Eigen::Isometry3d X_WT_ = Eigen::Isometry3d::Identity();  // the last tool pose given
  bool clutched_ = false;
  bool recentre_ = false;
};

}  // namespace microdex::station
