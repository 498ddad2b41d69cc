#pragma once
// The checks every external device sample passes before it reaches the simulation: a driver
// that stops sending (timeout_steps steps without a new sample: 10 ms at 1 kHz), sends a
// non-finite number, or jumps further in one sample than a hand can is a fault. During a fault
// the guard repeats the last valid sample (the tool is held) with the fault set; the step then
// ramps the force to zero (station_step.h) and the publisher raises a TaskEvent. The fault ends
// after resume_samples consecutive valid samples that agree with each other; the device's
// mapping then re-centres (as a clutch would) so that the tool does not jump.
//
// Plain state, no allocation: runs on the haptic thread.

#include <cstdint>

#include "station/device.h"

namespace microdex::station {

struct DeviceGuardDef {
  int timeout_steps = 10;    // without a new sample → kTimeout
  double max_jump_m = 0.01;  // between consecutive samples (10 m/s at 1 kHz) → kJump
  int resume_samples = 5;    // consecutive valid, consistent samples to end a fault
  // Throws std::invalid_argument("field: reason").
  void Validate() const;
};

// A sample as it came from a driver or a file (device frame; not yet mapped to the world).
struct RawDeviceSample {
  Eigen::Vector3d p_D = Eigen::Vector3d::Zero();  // m
  Eigen::Quaterniond q_D = Eigen::Quaterniond::Identity();
  double gripper = 0;
  std::uint32_t buttons = 0;
  std::uint64_t sample_step = 0;     // the driver's own counter (echoed in the force)
  std::int64_t sample_stamp_ns = 0;  // the driver's stamp (echoed)
};

class DeviceGuard {
 public:
  explicit DeviceGuard(const DeviceGuardDef& def = {});
  // One haptic step: `fresh` is the new sample of this step, or nullptr when none arrived.
  // Returns the sample to use (the last valid one during a fault) and sets *fault.
  // *resumed is true at the step a fault ended (the caller re-centres its mapping).
  const RawDeviceSample& Step(const RawDeviceSample* fresh, DeviceFault* fault, bool* resumed);
  DeviceFault fault() const { return fault_; }
  bool has_valid() const { return has_valid_; }

 private:
  DeviceGuardDef def_;
  RawDeviceSample last_valid_;
  RawDeviceSample last_seen_;
  bool has_valid_ = false;
  bool has_seen_ = false;
  int steps_without_ = 0;
  int consistent_ = 0;
  DeviceFault fault_ = DeviceFault::kNone;
};

}  // namespace microdex::station
