// The page device: the page's messages parsed and bounded; moves, turns, grip and buttons
// applied at the next Read on the haptic thread, the workspace box held, no allocation there.
#include "station/page_device.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "tests/support/alloc_counter.h"

namespace microdex::station {
namespace {

TEST(PageDevice, ParsesTheMessages) {
  const PageInput m = ParsePageInput("move 1e-3 -2e-4 0");
  EXPECT_EQ(m.kind, PageInput::Kind::kMove);
  EXPECT_EQ(m.v[1], -2e-4);
  EXPECT_EQ(ParsePageInput("turn 0 0 0.1").kind, PageInput::Kind::kTurn);
  EXPECT_EQ(ParsePageInput("grip 1").v[0], 1);
  EXPECT_EQ(ParsePageInput("buttons 3").buttons, 3u);
}

TEST(PageDevice, RefusesBadMessagesWithTheReason) {
  const std::pair<const char*, const char*> bad[] = {
      {"", "unknown device message"},
      {"move", "move: expected 3 finite numbers"},
      {"move 1 2", "move: expected 3 finite numbers"},
      {"move nan 0 0", "move: expected 3 finite numbers"},
      {"move inf 0 0", "move: expected 3 finite numbers"},
      {"move 3e-3 0 0", "move: longer than 2 mm"},
      {"move 0 0 0 0", "move: unexpected '0'"},
      {"turn 0.3 0 0", "turn: more than 0.2 rad"},
      {"grip -0.1", "grip: expected 0..1"},
      {"buttons 65536", "buttons: expected an integer"},
      {"buttons 2.5", "buttons: expected an integer"},
      {"teleport 0 0 0", "unknown device message 'teleport'"},
  };
  for (const auto& [text, why] : bad) {
    try {
      ParsePageInput(text);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << text << ": " << e.what();
    }
  }
}

TEST(PageDevice, AppliesInputsAtTheNextReadWithoutAllocating) {
  Eigen::Isometry3d X_start = Eigen::Isometry3d::Identity();
  X_start.translation() = Eigen::Vector3d(0.01, 0, 0.002);
  PageDevice device(X_start);
  EXPECT_TRUE(device.Read(0).X_WT.isApprox(X_start));
  ASSERT_TRUE(device.Push(ParsePageInput("move 1e-3 0 0")));
  ASSERT_TRUE(device.Push(ParsePageInput("move 0 5e-4 0")));
  ASSERT_TRUE(device.Push(ParsePageInput("turn 0 0 0.1")));
  ASSERT_TRUE(device.Push(ParsePageInput("grip 0.75")));
  ASSERT_TRUE(device.Push(ParsePageInput("buttons 2")));
  testing::StartCountingAllocations();
  const DeviceSample s = device.Read(1);
  const std::uint64_t allocations = testing::StopCountingAllocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_TRUE(s.X_WT.translation().isApprox(Eigen::Vector3d(0.011, 5e-4, 0.002), 1e-12));
  EXPECT_NEAR(Eigen::AngleAxisd(s.X_WT.linear()).angle(), 0.1, 1e-12);
  EXPECT_EQ(s.gripper, 0.75);
  EXPECT_EQ(s.buttons, 2u);
  // Nothing new: the same sample.
  EXPECT_TRUE(device.Read(2).X_WT.isApprox(s.X_WT));
}

TEST(PageDevice, KeepsTheToolInsideItsWorkspace) {
  PageDevice device(Eigen::Isometry3d::Identity());
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(device.Push(ParsePageInput("move 1.4e-3 0 -1.4e-3")));
  }
  const DeviceSample s = device.Read(0);
  EXPECT_DOUBLE_EQ(s.X_WT.translation().x(), PageDevice::kWorkspaceHalf_m);
  EXPECT_DOUBLE_EQ(s.X_WT.translation().z(), -PageDevice::kWorkspaceHalf_m);
}

TEST(PageDevice, AFullRingRefusesMoreInput) {
  PageDevice device(Eigen::Isometry3d::Identity());
  std::size_t pushed = 0;
  while (device.Push(ParsePageInput("grip 1")) && pushed < 10 * PageDevice::kRingCapacity) ++pushed;
  EXPECT_EQ(pushed, PageDevice::kRingCapacity);
}

}  // namespace
}  // namespace microdex::station
