#pragma once
// --device playback FILE: a recorded input stream, one row per haptic step, from a CSV file
// with a header line and the columns
//     p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons
// (the tool pose in world, m; quaternion (w, x, y, z); gripper 0..1; buttons an integer bit
// mask) — what the station publishes as DeviceInput, so a recorded session plays back as it
// was. After the last row the last pose is held. Rows pass the device guard like a driver's
// samples (a NaN row is a fault: the tool is held and the force ramps to zero).

#include <string>
#include <vector>

#include "station/device.h"
#include "station/device_guard.h"

namespace microdex::station {

class PlaybackDevice final : public Device {
 public:
  // Reads the whole file; throws InputError ("FILE:LINE: column: reason") on a malformed one.
  explicit PlaybackDevice(const std::string& path);
  DeviceSample Read(std::uint64_t step) override;
  void WriteForce(const Eigen::Vector3d& f_T_W) override { last_force_ = f_T_W; }
  std::size_t rows() const { return rows_.size(); }
  const Eigen::Vector3d& last_force() const { return last_force_; }

 private:
  std::vector<RawDeviceSample> rows_;
  DeviceGuard guard_;
  Eigen::Vector3d last_force_ = Eigen::Vector3d::Zero();
};

}  // namespace microdex::station
