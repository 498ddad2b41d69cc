// Knot placement: a button press records a stitch at the tool tip's azimuth and bite; the
// spacing error is zero for stitches evenly spaced, and against a hand computation otherwise;
// missing stitches count as whole gaps.
#include "station/placement_module.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <numbers>

#include "common/scene/scene.h"
#include "station/snapshot.h"
#include "station/station_step.h"

namespace microdex::station {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(PlacementModule, RecordsStitchesAndScoresTheirSpacing) {
  scene::PlacementSceneDef def;
  def.stitches = 4;
  def.bite_m = 0.3e-3;
  def.end_height_m = 6e-3;
  state::PlacementState p;
  // Evenly spaced (any rotation), exact bites: no error.
  p.count = 4;
  for (int i = 0; i < 4; ++i) {
    p.azimuth_rad[i] = std::fmod(0.3 + i * kPi / 2, 2 * kPi);
    p.bite_m[i] = 0.3e-3;
  }
  PlacementErrors e = CalcPlacementErrors(def, p);
  EXPECT_NEAR(e.spacing_rms_rad, 0, 1e-12);
  EXPECT_NEAR(e.bite_rms_m, 0, 1e-15);
  // One stitch moved by 0.2 rad: two gaps off by ±0.2 → RMS 0.2 √(2/4).
  p.azimuth_rad[1] += 0.2;
  p.bite_m[2] = 0.5e-3;
  e = CalcPlacementErrors(def, p);
  EXPECT_NEAR(e.spacing_rms_rad, 0.2 * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(e.bite_rms_m, 0.2e-3 / 2, 1e-15);
  // Two stitches only, opposite: two gaps of π against π/2, and two missing gaps of π/2.
  p.count = 2;
  p.azimuth_rad[0] = 0;
  p.azimuth_rad[1] = kPi;
  e = CalcPlacementErrors(def, p);
  EXPECT_NEAR(e.spacing_rms_rad,
              std::sqrt((2 * std::pow(kPi / 2, 2) + 2 * std::pow(kPi / 2, 2)) / 4), 1e-12);
}

TEST(PlacementModule, ButtonPressPlacesAStitchAtTheTip) {
  scene::SceneModel scene;
  scene.placement = scene::PlacementSceneDef{};
  PlacementModule m(scene);
  state::StationState s;
  m.InitState(s);
  ToolInput in;
  in.X_WT.translation() = Eigen::Vector3d(0, -0.5e-3, 5.6e-3);  // azimuth 3π/2, bite 0.4 mm
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  s.tool.buttons = 1;
  m.Step(in, s, f);
  m.Step(in, s, f);  // held: still one stitch
  ASSERT_EQ(s.placement->count, 1);
  EXPECT_NEAR(s.placement->azimuth_rad[0], 1.5 * kPi, 1e-12);
  EXPECT_NEAR(s.placement->bite_m[0], 0.4e-3, 1e-15);
  s.tool.buttons = 0;
  m.Step(in, s, f);
  s.tool.buttons = 1;
  m.Step(in, s, f);
  EXPECT_EQ(s.placement->count, 2);
  EXPECT_EQ(f, Eigen::Vector3d::Zero());
}

// The stitches placed reach the tick's snapshot, from which the mirrored tool state and the
// view frames carry them to the pages.
TEST(PlacementModule, TheStitchesPlacedReachTheSnapshot) {
  const scene::SceneModel scene = scene::LoadScene(
      std::string(std::getenv("MICRODEX_SOURCE_DIR") ? std::getenv("MICRODEX_SOURCE_DIR") : ".") +
      "/assets/scenes/knot_placement.yaml");
  Simulation sim(scene);
  state::StationState s = sim.MakeInitialState(3);
  const double h = scene.placement->end_height_m;
  const double r = scene.placement->vessel_radius_m;
  for (int k = 0; k < 3; ++k) {
    const double a = 0.5 + 2.0 * k;
    StationInput in;
    in.device.X_WT.translation() = Eigen::Vector3d(r * std::cos(a), r * std::sin(a), h - 0.3e-3);
    for (const std::uint32_t buttons : {0u, 1u}) {
      in.device.buttons = buttons;
      StepStation(sim, in, s);
    }
  }
  ASSERT_EQ(s.placement->count, 3);
  auto snap = std::make_unique<TickSnapshot>();
  ProjectSnapshot(sim, s, *snap);
  ASSERT_EQ(snap->stitch_count, 3);
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    EXPECT_EQ(snap->stitch_azimuth_rad[i], static_cast<float>(s.placement->azimuth_rad[i]));
    EXPECT_EQ(snap->stitch_bite_m[i], static_cast<float>(s.placement->bite_m[i]));
  }
}

}  // namespace
}  // namespace microdex::station
