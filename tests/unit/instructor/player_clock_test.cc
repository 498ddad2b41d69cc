// The replay's PlayerClock on an injected wall clock: session time runs at the speed, stands
// still while paused, steps only while paused, keeps its place when the speed changes, and
// WallTimeOf answers when a session time is reached (never while paused and ahead). And where
// a replay finds a recorded scene (FindRecordedScene).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "instructor/replay_player.h"

namespace microdex::instructor {
namespace {

std::int64_t g_now_ns = 0;
std::int64_t FakeNow() { return g_now_ns; }

constexpr std::int64_t kStart = 1'000'000'000'000;  // session time of the first message
constexpr std::int64_t kMs = 1'000'000;

TEST(PlayerClock, RunsAtItsSpeedPausesStepsAndChangesSpeedInPlace) {
  g_now_ns = 5'000 * kMs;
  PlayerClock c(kStart, 2.0, &FakeNow);
  EXPECT_EQ(c.SessionNowNs(), kStart);
  g_now_ns += 100 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 200 * kMs);  // 2x
  EXPECT_EQ(*c.WallTimeOf(kStart + 300 * kMs), g_now_ns + 50 * kMs);

  c.TogglePause();
  EXPECT_TRUE(c.paused());
  g_now_ns += 1'000 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 200 * kMs);  // stands still
  EXPECT_FALSE(c.WallTimeOf(kStart + 201 * kMs).has_value());
  EXPECT_EQ(*c.WallTimeOf(kStart + 150 * kMs), g_now_ns);  // already reached: now
  c.Step(100 * kMs);
  EXPECT_EQ(c.SessionNowNs(), kStart + 300 * kMs);
  c.TogglePause();
  EXPECT_FALSE(c.paused());
  g_now_ns += 50 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 400 * kMs);
  c.Step(100 * kMs);  // ignored while playing
  EXPECT_EQ(c.SessionNowNs(), kStart + 400 * kMs);

  c.SetSpeed(0.5);
  EXPECT_EQ(c.SessionNowNs(), kStart + 400 * kMs);  // no jump
  g_now_ns += 100 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 450 * kMs);
  c.SetSpeed(1e9);
  EXPECT_EQ(c.speed(), 1024.0);  // clamped
  c.SetSpeed(0);
  EXPECT_EQ(c.speed(), 1.0 / 64);

  c.Restart();  // the wall clock restarts; session time stays
  g_now_ns += 64 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 451 * kMs);
}

// A seek jumps to the time sought, back or on, and keeps the speed and the pause; every seek
// is counted (the player restarts from the time on a new count).
TEST(PlayerClock, SeekJumpsBackOrOnKeepingSpeedAndPause) {
  g_now_ns = 7'000 * kMs;
  PlayerClock c(kStart, 2.0, &FakeNow);
  g_now_ns += 500 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 1'000 * kMs);
  EXPECT_EQ(c.seeks(), 0u);
  c.Seek(kStart + 200 * kMs);  // back
  EXPECT_EQ(c.seeks(), 1u);
  EXPECT_EQ(c.SessionNowNs(), kStart + 200 * kMs);
  g_now_ns += 100 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 400 * kMs) << "at ×2 from the time sought";
  EXPECT_EQ(c.WallTimeOf(kStart + 600 * kMs), g_now_ns + 100 * kMs);
  c.TogglePause();
  c.Seek(kStart + 5'000 * kMs);  // on, while paused
  EXPECT_EQ(c.seeks(), 2u);
  g_now_ns += 1'000 * kMs;
  EXPECT_TRUE(c.paused());
  EXPECT_EQ(c.SessionNowNs(), kStart + 5'000 * kMs) << "paused where it was sought to";
  EXPECT_FALSE(c.WallTimeOf(kStart + 5'001 * kMs).has_value());
  c.TogglePause();
  g_now_ns += 50 * kMs;
  EXPECT_EQ(c.SessionNowNs(), kStart + 5'100 * kMs);
}

// Where a replay looks for a recorded station's scene: the recorded path if it is a file, else
// the file of that name in the scene folder; nothing for a folder, a missing file, or no path.
TEST(FindRecordedScene, RecordedPathFirstThenByNameInTheSceneFolder) {
  namespace fs = std::filesystem;
  const fs::path root =
      fs::temp_directory_path() / ("microdex-find-scene-" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "here" / "assets");
  fs::create_directories(root / "scenes" / "a.yaml");  // a folder of that name is no scene
  std::ofstream(root / "here" / "assets" / "a.yaml") << "name: a\n";
  std::ofstream(root / "scenes" / "b.yaml") << "name: b\n";
  const std::string here = (root / "here" / "assets" / "a.yaml").string();
  const std::string dir = (root / "scenes").string();
  EXPECT_EQ(FindRecordedScene(here, dir), here);
  EXPECT_EQ(FindRecordedScene(here, ""), here);
  EXPECT_EQ(FindRecordedScene("elsewhere/assets/b.yaml", dir),
            (root / "scenes" / "b.yaml").string());
  EXPECT_EQ(FindRecordedScene("elsewhere/assets/b.yaml", ""), "");
  EXPECT_EQ(FindRecordedScene("elsewhere/a.yaml", dir), "");  // scenes/a.yaml is a folder
  EXPECT_EQ(FindRecordedScene("elsewhere/c.yaml", dir), "");
  EXPECT_EQ(FindRecordedScene("", dir), "");
  fs::remove_all(root);
}

}  // namespace
}  // namespace microdex::instructor
