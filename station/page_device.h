#pragma once
// The view page's keyboard and mouse as a haptic device (`--device page`): the page sends
// small moves of the tool (world frame, already turned from the view's axes by the page), turns,
// the gripper and the buttons over its WebSocket; the view server's thread parses them
// (ParsePageInput) and pushes them through an SpscRing; the haptic thread applies every
// pending one at its next Read. The tool starts at the task's start pose and is kept inside a
// box of kWorkspaceHalf_m around it. No force is rendered (a keyboard has no motor).

#include <array>
#include <cstdint>
#include <string>

#include "station/device.h"
#include "station/rt/spsc_ring.h"

namespace microdex::station {

struct PageInput {
  enum class Kind : std::uint8_t { kMove, kTurn, kGrip, kButtons };
  Kind kind = Kind::kMove;
  std::array<double, 3> v{};  // move: m (world); turn: rotation vector, rad (world); grip: v[0]
  std::uint32_t buttons = 0;
};

// Bounds of one message.
inline constexpr double kMaxPageMove_m = 2e-3;
inline constexpr double kMaxPageTurn_rad = 0.2;

// Parses one text message of the page: "move DX DY DZ" (m), "turn RX RY RZ" (rad),
// "grip G" (0..1), "buttons B" (0..2^16). Throws std::invalid_argument naming what is wrong.
PageInput ParsePageInput(const std::string& message);

class PageDevice : public Device {
 public:
  static constexpr double kWorkspaceHalf_m = 0.03;
  static constexpr std::size_t kRingCapacity = 256;

  explicit PageDevice(const Eigen::Isometry3d& X_WT_start);

  // View server thread (the ring's producer). False when the ring is full (input dropped).
  bool Push(const PageInput& input) { return ring_.TryPush(input); }

  // Haptic thread (the consumer): applies the pending inputs; never allocates or blocks.
  DeviceSample Read(std::uint64_t step) override;
  void WriteForce(const Eigen::Vector3d& f_T_W) override { last_force_ = f_T_W; }

 private:
  rt::SpscRing<PageInput> ring_;  // producer: view server thread; consumer: haptic thread
  Eigen::Vector3d p_W_start_;
  DeviceSample sample_;
  Eigen::Vector3d last_force_ = Eigen::Vector3d::Zero();
};

}  // namespace microdex::station
