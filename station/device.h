#pragma once
// A haptic device as the haptic thread sees it: read a pose once per step, write a force.
// Implementations never allocate, lock, log or block in Read/WriteForce (WaitForSample is the
// one place a device may wait: it paces the tick).

#include <Eigen/Geometry>
#include <cstdint>

namespace microdex::station {

// Why a device's sample could not be used (the station then holds the tool where it was,
// ramps the force to zero and raises a TaskEvent; it resumes when valid samples return).
enum class DeviceFault : std::uint8_t {
  kNone = 0,
  kTimeout = 1,    // no new sample for DeviceGuardDef::timeout_steps steps (10 ms)
  kNonFinite = 2,  // a NaN or infinite number in the sample
  kJump = 3,       // the pose moved further in one sample than a hand can
};
const char* DeviceFaultName(DeviceFault fault);

struct DeviceSample {
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  // tool pose in world, m
  double gripper = 0;                                      // 0 open .. 1 closed
  std::uint32_t buttons = 0;
  DeviceFault fault = DeviceFault::kNone;  // kNone: the pose is the device's; else held
};

class Device {
 public:
  virtual ~Device() = default;
  // The sample for `step`; steps arrive in order, one per call.
  virtual DeviceSample Read(std::uint64_t step) = 0;
  // The force on the tool, expressed in world (finite and limited by the caller).
  virtual void WriteForce(const Eigen::Vector3d& f_T_W) = 0;
  // Force and torque (about the tool point), both in world, finite and limited by the caller:
  // what the haptic loop calls. A device that renders no torque keeps this default.
  virtual void WriteWrench(const Eigen::Vector3d& f_T_W, const Eigen::Vector3d& /*tau_T_W*/) {
    WriteForce(f_T_W);
  }
  // A device that paces the loop (an external driver's 1 kHz servo loop): WaitForSample
  // returns as soon as a new sample has arrived (true) or at until_ns on the monotonic clock
  // (false). Others are paced by the loop's own deadlines.
  virtual bool paces_loop() const { return false; }
  virtual bool WaitForSample(std::int64_t /*until_ns*/) { return false; }
};

// A tool held still at a pose with its gripper closed: the second tool of a bimanual scene
// when the first is driven from the view page (keyboard and mouse drive one tool).
class HeldDevice final : public Device {
 public:
  explicit HeldDevice(const Eigen::Isometry3d& X_WT) { sample_.X_WT = X_WT, sample_.gripper = 1; }
  DeviceSample Read(std::uint64_t /*step*/) override { return sample_; }
  void WriteForce(const Eigen::Vector3d& /*f_T_W*/) override {}

 private:
  DeviceSample sample_;
};

}  // namespace microdex::station
