// The station's tissue module against the capacity of a disk in a square: a point tool with
// contact radius a pressed U deep at the centre of an L × L patch held at its edges needs
// F = 2π G t U / ln(R / a), R = Γ(1/4)² / (4 π^{3/2}) L the inner (conformal) radius of the
// square about its centre (the antiplane problem is Laplace's equation, G t ∇²w = 0, w = −U on
// the disk, 0 on the edges). Also: the force is linear in the depth, the world force does not
// depend on how the patch frame is placed, nothing touches above the surface, and the frame
// holds the field on the display grid (−U under the tool, 0 on the edges).
#include "station/tissue_module.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>

namespace microdex::station {
namespace {

std::string SceneDir() {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes";
}

// The skin patch (2 × 2 cm, G = 20 kPa, t = 2 mm) centred on the world origin.
scene::SceneModel TissueScene(int level,
                              const std::string& frame = "position_m: [-0.01, -0.01, 0]") {
  return scene::ParseScene(R"(
name: test-tissue
modules: [tissue]
tissue:
  params: tissue_skin_patch.yaml
  )" + frame + R"(
  level: )" + std::to_string(level) +
                               R"(
  solver: pcg_ic
  tool: point
  contact_radius_m: 0.5e-3
  display_level: 5
task: {path: line, line_start_m: [0, 0, 0.001], line_end_m: [0, 0, -0.001]}
haptic: {rate_hz: 1000, max_force_N: 2.0}
)",
                           SceneDir() + "/inline.yaml");
}

// The module and its state, as a station holds them.
struct Tissue {
  explicit Tissue(const scene::SceneModel& scene) : m(scene) { m.InitState(s); }
  const fem::TissueState& state() const { return s.tissue->tissue; }
  ModuleStatus status() const { return m.Status(s); }
  TissueModule m;
  state::StationState s;
};

Eigen::Vector3d PressAt(Tissue& t, const Eigen::Vector3d& p_WT, int steps = 3) {
  ToolInput in;
  in.X_WT = Eigen::Isometry3d::Identity();
  in.X_WT.translation() = p_WT;
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  for (int k = 0; k < steps; ++k) {
    f.setZero();
    in.step = static_cast<std::uint64_t>(k);
    t.m.Step(in, t.s, f);
  }
  return f;
}

double DiskCapacityForce_N(const fem::TissueDef& def, double contact_radius_m, double depth_m) {
  const double inner_radius_m = std::tgamma(0.25) * std::tgamma(0.25) /
                                (4 * std::pow(std::numbers::pi, 1.5)) * def.length_x_m;
  return 2 * std::numbers::pi * def.shear_modulus_Pa * def.thickness_m * depth_m /
         std::log(inner_radius_m / contact_radius_m);
}

TEST(TissueModule, PressedPointMatchesTheDiskCapacity) {
  constexpr double kDepth_m = 1e-3;
  double previous_error = 1;
  for (int level : {6, 7}) {
    const scene::SceneModel scene = TissueScene(level);
    Tissue m(scene);
    const Eigen::Vector3d f = PressAt(m, Eigen::Vector3d(0, 0, -kDepth_m));
    const double ref_N = DiskCapacityForce_N(scene.tissue->def, 0.5e-3, kDepth_m);
    const double error = std::abs(f.z() - ref_N) / ref_N;
    std::printf("level %d: F = %.5f N, disk capacity %.5f N, error %.2f %%\n", level, f.z(), ref_N,
                100 * error);
    EXPECT_EQ(m.state().status, fem::TissueStatus::kOk);
    EXPECT_GT(f.z(), 0) << "the tissue pushes the tool back up";
    EXPECT_NEAR(f.x(), 0, 1e-9);
    EXPECT_NEAR(f.y(), 0, 1e-9);
    EXPECT_LT(m.status().error_estimate, 1e-6) << "relative residual of the solve";
    // The discrete disk (grid nodes within a) and the P1 field near it set the error: of order
    // (h / a) / ln(R / a), a few per cent at cells of 0.31 and 0.16 mm.
    // station/README.md states 3.2 % at level 6 and 2.3 % at level 7.
    EXPECT_LT(error, level == 6 ? 0.033 : 0.024) << "level " << level;
    EXPECT_LT(error, previous_error) << "the error must fall as the mesh is refined";
    previous_error = error;
  }
}

TEST(TissueModule, ForceIsLinearInDepthAndZeroAboveTheSurface) {
  const scene::SceneModel scene = TissueScene(6);
  Tissue a(scene), b(scene), c(scene);
  const Eigen::Vector3d f1 = PressAt(a, Eigen::Vector3d(1e-3, -2e-3, -0.4e-3));
  const Eigen::Vector3d f2 = PressAt(b, Eigen::Vector3d(1e-3, -2e-3, -0.8e-3));
  EXPECT_GT(f1.z(), 0);
  EXPECT_NEAR(f2.z(), 2 * f1.z(), 1e-6 * f1.z());
  const Eigen::Vector3d f0 = PressAt(c, Eigen::Vector3d(1e-3, -2e-3, 0.2e-3));
  EXPECT_EQ(f0, Eigen::Vector3d::Zero());
  EXPECT_EQ(c.state().status, fem::TissueStatus::kNoContact);
  EXPECT_FALSE(c.status().fault);
}

TEST(TissueModule, WorldForceDoesNotDependOnThePatchFrame) {
  // The same world square, its frame turned by 90° about z (corner at (+L/2, −L/2)) and by
  // 180° about x (the patch upside down, its surface normal −z, corner at (−L/2, +L/2)), with
  // the tool pressing along the respective normals.
  const scene::SceneModel plain = TissueScene(6);
  const scene::SceneModel turned =
      TissueScene(6, "position_m: [0.01, -0.01, 0]\n  rpy_rad: [0, 0, 1.5707963267948966]");
  const scene::SceneModel flipped =
      TissueScene(6, "position_m: [-0.01, 0.01, 0]\n  rpy_rad: [3.141592653589793, 0, 0]");
  Tissue a(plain), b(turned), c(flipped);
  const Eigen::Vector3d fa = PressAt(a, Eigen::Vector3d(0, 0, -0.7e-3));
  const Eigen::Vector3d fb = PressAt(b, Eigen::Vector3d(0, 0, -0.7e-3));
  const Eigen::Vector3d fc = PressAt(c, Eigen::Vector3d(0, 0, 0.7e-3));
  EXPECT_NEAR((fb - fa).norm(), 0, 1e-6 * fa.norm());
  EXPECT_NEAR((fc + fa).norm(), 0, 1e-6 * fa.norm()) << "the flipped patch pushes along −z";
}

TEST(TissueModule, FrameHoldsTheFieldOnTheDisplayGrid) {
  const scene::SceneModel scene = TissueScene(6);
  Tissue m(scene);
  constexpr double kDepth_m = 0.6e-3;
  PressAt(m, Eigen::Vector3d(0, 0, -kDepth_m));
  auto frames = std::make_unique<LargeFrames>();
  m.m.WriteFrame(m.s, 5, 77, *frames);
  ASSERT_TRUE(frames->tissue.Update());
  const TissueFrame& f = frames->tissue.front();
  const std::uint32_t side = (1u << scene.tissue->display_level) + 1;
  ASSERT_EQ(f.nodes_x, side);
  ASSERT_EQ(f.nodes_y, side);
  EXPECT_EQ(f.step, 5u);
  EXPECT_NEAR(f.max_displacement_m, kDepth_m, 1e-12);
  // Interpolation on the display grid leaves rounding of order 1e-18 of the depth.
  constexpr double kRoundoff_m = 1e-15;
  // The centre node is under the tool (float precision); the edges are held.
  EXPECT_NEAR(f.w_m[(side / 2) * side + side / 2], -kDepth_m, 1e-6 * kDepth_m);
  for (std::uint32_t i = 0; i < side; ++i) {
    EXPECT_NEAR(f.w_m[i], 0.0, kRoundoff_m);
    EXPECT_NEAR(f.w_m[(side - 1) * side + i], 0.0, kRoundoff_m);
    EXPECT_NEAR(f.w_m[i * side], 0.0, kRoundoff_m);
    EXPECT_NEAR(f.w_m[i * side + side - 1], 0.0, kRoundoff_m);
  }
  // Maximum principle: nothing deeper than the tool, nothing above the surface.
  for (std::uint32_t k = 0; k < side * side; ++k) {
    EXPECT_LE(f.w_m[k], kRoundoff_m);
    EXPECT_GE(f.w_m[k], -kDepth_m * (1 + 1e-6));
  }
}

}  // namespace
}  // namespace microdex::station
