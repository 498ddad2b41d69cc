#pragma once
// A haptic device as the haptic thread sees it: read a pose once per step, write a force.
// Implementations never allocate, lock, log or block in Read/WriteForce.

#include <Eigen/Geometry>
#include <cstdint>

namespace microdex::station {

struct DeviceSample {
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  // tool pose in world, m
  double gripper = 0;                                      // 0 open .. 1 closed
  std::uint32_t buttons = 0;
};

class Device {
 public:
  virtual ~Device() = default;
  // The sample for `step`; steps arrive in order, one per call.
  virtual DeviceSample Read(std::uint64_t step) = 0;
  // The force on the tool, expressed in world (finite and saturated by the caller).
  virtual void WriteForce(const Eigen::Vector3d& f_T_W) = 0;
};

}  // namespace microdex::station
