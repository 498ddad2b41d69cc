#include "station/device_guard.h"

#include <cmath>
#include <stdexcept>

namespace microdex::station {
namespace {

bool Finite(const RawDeviceSample& s) {
  return s.p_D.allFinite() && s.q_D.coeffs().allFinite() && std::isfinite(s.gripper) &&
         s.q_D.coeffs().norm() > 0.5;
}

}  // namespace

const char* DeviceFaultName(DeviceFault fault) {
  switch (fault) {
    case DeviceFault::kNone:
      return "ok";
    case DeviceFault::kTimeout:
      return "no sample for 10 ms";
    case DeviceFault::kNonFinite:
      return "non-finite sample";
    case DeviceFault::kJump:
      return "sample jumped";
  }
  return "unknown";
}

void DeviceGuardDef::Validate() const {
  if (timeout_steps < 1) throw std::invalid_argument("timeout_steps: expected >= 1");
  if (!(max_jump_m > 0 && std::isfinite(max_jump_m))) {
    throw std::invalid_argument("max_jump_m: expected > 0");
  }
  if (resume_samples < 1) throw std::invalid_argument("resume_samples: expected >= 1");
}

DeviceGuard::DeviceGuard(const DeviceGuardDef& def) : def_(def) { def_.Validate(); }

const RawDeviceSample& DeviceGuard::Step(const RawDeviceSample* fresh, DeviceFault* fault,
                                         bool* resumed) {
  *resumed = false;
  if (fresh == nullptr) {
    if (++steps_without_ >= def_.timeout_steps && has_valid_) {
      fault_ = DeviceFault::kTimeout;
      consistent_ = 0;
    }
    *fault = has_valid_ ? fault_ : DeviceFault::kTimeout;
    return last_valid_;
  }
  steps_without_ = 0;
  if (!Finite(*fresh)) {
    fault_ = DeviceFault::kNonFinite;
    consistent_ = 0;
    *fault = fault_;
    return last_valid_;
  }
  const bool jumped_from_seen = has_seen_ && (fresh->p_D - last_seen_.p_D).norm() > def_.max_jump_m;
  last_seen_ = *fresh;
  has_seen_ = true;
  if (!has_valid_) {  // the first sample
    last_valid_ = *fresh;
    last_valid_.q_D.normalize();
    has_valid_ = true;
    *fault = fault_ = DeviceFault::kNone;
    return last_valid_;
  }
  if (fault_ == DeviceFault::kNone) {
    if (jumped_from_seen) {
      fault_ = DeviceFault::kJump;
      consistent_ = 1;  // this sample starts a run of consistent ones
      *fault = fault_;
      return last_valid_;
    }
    last_valid_ = *fresh;
    last_valid_.q_D.normalize();
    *fault = fault_;
    return last_valid_;
  }
  // In a fault: resume after resume_samples consecutive valid samples close to each other.
  consistent_ = jumped_from_seen ? 1 : consistent_ + 1;
  if (consistent_ >= def_.resume_samples) {
    fault_ = DeviceFault::kNone;
    consistent_ = 0;
    last_valid_ = *fresh;
    last_valid_.q_D.normalize();
    *resumed = true;
  }
  *fault = fault_;
  return last_valid_;
}

}  // namespace microdex::station
