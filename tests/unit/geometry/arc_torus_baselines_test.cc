// The baselines (sampled and mesh) against the exact clearance: what each can and cannot
// get wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <utility>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/arc_torus_mesh.h"
#include "common/geometry/arc_torus_sampled.h"
#include "common/mesh/mesh_io.h"
#include "common/mesh/primitives.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(ArcTorusSampled, NeverDeeperThanExactAndConvergesQuadratically) {
  std::mt19937_64 rng(11);
  // Worst error over the whole-torus cases (no range boundary) for 1000 and 4000 samples.
  double worst[2] = {0, 0};
  for (int i = 0; i < 3000; ++i) {
    const auto c = testing::MakeNearCoreArcTorus(rng);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    if (exact.status != ClearanceStatus::kOk) continue;
    const double R = c.torus.core_radius_m;
    for (int k = 0; k < 2; ++k) {
      const ArcTorusClearance sampled =
          CalcArcTorusClearanceSampled(c.arc, c.torus, k == 0 ? 1000 : 4000);
      if (sampled.status != ClearanceStatus::kOk) continue;
      // Samples are needle points in range: their deepest can only be shallower.
      EXPECT_GE(sampled.clearance_m, exact.clearance_m - 1e-12 * R) << i;
      if (c.torus.segment_angle_rad >= 2 * kPi) {
        worst[k] = std::max(worst[k], (sampled.clearance_m - exact.clearance_m) / R);
      }
    }
  }
  // A smooth maximum is missed by O(h²): four times the samples, a sixteenth of the error
  // (a factor 8 allowed for where the worst case falls on the grid).
  EXPECT_GT(worst[0], 0);
  EXPECT_LT(worst[1], worst[0] / 8);
}

// On segments, where the deepest point is often on an end plane: the clipped sampling is
// never deeper than exact and converges quadratically; the plain one only linearly.
TEST(ArcTorusSampled, ClippedSamplingConvergesQuadraticallyOnSegments) {
  std::mt19937_64 rng(14);
  double worst_clipped[2] = {0, 0}, worst_plain[2] = {0, 0};
  for (int i = 0; i < 3000; ++i) {
    auto c = testing::MakeNearCoreArcTorus(rng);
    c.torus.segment_angle_rad = 0.5 + 0.002 * i;
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    if (exact.status != ClearanceStatus::kOk) continue;
    const double R = c.torus.core_radius_m;
    for (int k = 0; k < 2; ++k) {
      const int n = k == 0 ? 100 : 1600;
      const ArcTorusClearance clipped = CalcArcTorusClearanceSampledClipped(c.arc, c.torus, n);
      ASSERT_EQ(clipped.status, ClearanceStatus::kOk) << i;
      EXPECT_GE(clipped.clearance_m, exact.clearance_m - 1e-12 * R) << i;
      worst_clipped[k] = std::max(worst_clipped[k], (clipped.clearance_m - exact.clearance_m) / R);
      const ArcTorusClearance plain = CalcArcTorusClearanceSampled(c.arc, c.torus, n);
      if (plain.status == ClearanceStatus::kOk) {
        worst_plain[k] = std::max(worst_plain[k], (plain.clearance_m - exact.clearance_m) / R);
      }
    }
  }
  EXPECT_GT(worst_clipped[0], 0);
  // 16 times the samples: ~1/256 of the error if quadratic, ~1/16 if linear (a missed
  // boundary); a factor 4 allowed for where the worst case falls on the grid.
  EXPECT_LT(worst_clipped[1], worst_clipped[0] / 64);
  EXPECT_GT(worst_plain[1], worst_plain[0] / 64);
  EXPECT_LT(worst_clipped[1], worst_plain[1]);
}

TEST(ArcTorusSampled, EmptyAndInvalid) {
  ArcDef arc;
  TorusSegmentDef torus;
  torus.segment_angle_rad = 1;
  arc.radius_m = torus.core_radius_m;
  arc.sweep_rad = 1;
  arc.X_WN.linear() = Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_EQ(CalcArcTorusClearanceSampled(arc, torus, 100).status, ClearanceStatus::kEmptyRange);
  torus.tube_radius_m = 2 * torus.core_radius_m;
  EXPECT_EQ(CalcArcTorusClearanceSampled(arc, torus, 100).status, ClearanceStatus::kInvalidInput);
}

// The wall file the model writes and loads is common/mesh's open torus tube (no end caps), read
// back through assimp to float precision; the needle file is the ribbon.
TEST(ArcTorusMesh, WritesTheOpenTorusTubeAndTheRibbon) {
  const std::string dir = ::testing::TempDir() + "/arc_torus_mesh_files";
  std::filesystem::remove_all(dir);
  ArcDef arc;
  TorusSegmentDef torus;
  torus.segment_angle_rad = kPi;
  const MeshResolution res{12, 24, 6};
  const ArcTorusMeshModel model(arc, torus, res, dir);
  const mesh::TriangleMesh wall = mesh::MakeTorusTubeMesh({.core_radius_m = torus.core_radius_m,
                                                           .tube_radius_m = torus.tube_radius_m,
                                                           .segment_angle_rad = kPi,
                                                           .n_major = 12,  // 24 over a half turn
                                                           .n_minor = 6,
                                                           .end_caps = false});
  const mesh::TriangleMesh ribbon =
      MakeNeedleRibbonMesh(arc.radius_m, arc.sweep_rad, 12, 1e-6 * arc.radius_m);
  for (const auto& [path, generated] :
       {std::pair{model.vessel_path(), wall}, std::pair{model.needle_path(), ribbon}}) {
    const mesh::TriangleMesh loaded = mesh::LoadMesh(path);
    ASSERT_EQ(loaded.triangles.size(), generated.triangles.size()) << path;
    for (size_t t = 0; t < generated.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d a = generated.vertices[generated.triangles[t][k]];
        const Eigen::Vector3d b = loaded.vertices[loaded.triangles[t][k]];
        EXPECT_LT((a - b).norm(), 1e-9) << path << " " << t;  // assimp stores floats
      }
    }
  }
  EXPECT_EQ(model.num_triangles(),
            static_cast<int>(wall.triangles.size() + ribbon.triangles.size()));
  // An open tube: its two end rings are the only boundary.
  EXPECT_EQ(mesh::CalcEdgeTopology(mesh::LoadMesh(model.vessel_path())).boundary_edges, 2 * 6);
}

TEST(ArcTorusMesh, ApproachesExactClearanceAsTheMeshesRefine) {
  const std::string dir = ::testing::TempDir() + "/arc_torus_mesh_test";
  std::filesystem::remove_all(dir);
  ArcDef arc;
  TorusSegmentDef torus;
  arc.radius_m = torus.core_radius_m;
  arc.sweep_rad = 0.75 * kPi;
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1, 1);
  const double r = torus.tube_radius_m;
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 40; ++i) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::AngleAxisd(kPi * u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X.translation() = 0.4 * r * Eigen::Vector3d(u(rng), u(rng), u(rng));
    poses.push_back(X);
  }
  double previous_max_error = 1e9;
  for (const MeshResolution& res :
       {MeshResolution{16, 32, 8}, MeshResolution{64, 128, 32}, MeshResolution{128, 256, 64}}) {
    const ArcTorusMeshModel model(arc, torus, res, dir);
    EXPECT_TRUE(std::filesystem::exists(model.vessel_path()));
    double max_error = 0;
    for (const Eigen::Isometry3d& X_WN : poses) {
      arc.X_WN = X_WN;
      const ArcTorusClearance exact = CalcArcTorusClearanceExact(arc, torus);
      const ArcTorusClearance mesh = model.Calc(X_WN, torus.X_WV);
      ASSERT_EQ(mesh.status, ClearanceStatus::kOk);
      ASSERT_FALSE(exact.contact);
      // Inscribed meshes: the wall is drawn in, the needle chords cut inwards; the mesh
      // clearance is an underestimate up to the sagittas.
      EXPECT_FALSE(mesh.contact);
      max_error = std::max(max_error, std::abs(mesh.clearance_m - exact.clearance_m));
    }
    EXPECT_LT(max_error, previous_max_error / 2);
    previous_max_error = max_error;
  }
  EXPECT_LT(previous_max_error, 1e-2 * r);
}

// Needles whose deepest point is an end, close to the wall (the vertex–face case of the
// triangle distance): the mesh clearance is within the sum of the three sagittas of the exact
// one. FCL's triangle distance skips that case for facets whose squared edge cross product is
// below 1e-15 (millimetre-scale facets in metres): the model works in units of R.
TEST(ArcTorusMesh, WithinTheSagittasWhereANeedleEndIsDeepest) {
  const std::string dir = ::testing::TempDir() + "/arc_torus_mesh_test_ends";
  ArcDef arc;
  TorusSegmentDef torus;
  torus.X_WV.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.5).normalized()).matrix();
  torus.X_WV.translation() = Eigen::Vector3d(0.02, -0.01, 0.03);
  const double R = torus.core_radius_m, r = torus.tube_radius_m;
  arc.radius_m = R;
  arc.sweep_rad = 0.75 * kPi;
  const MeshResolution res{256, 512, 128};
  const ArcTorusMeshModel model(arc, torus, res, dir);
  // Chord sagittas: the wall around the core (outer equator) and around the tube, the needle.
  const double sagittas = (R + r) * (1 - std::cos(kPi / res.n_major)) +
                          r * (1 - std::cos(kPi / res.n_minor)) +
                          arc.radius_m * (1 - std::cos(arc.sweep_rad / (2 * res.needle_segments)));
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0;
  for (int i = 0; i < 2000 && checked < 40; ++i) {
    Eigen::Isometry3d X_VN = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    X_VN.linear() = (Eigen::AngleAxisd(0.9 * r / R * std::abs(u(rng)), axis) *
                     Eigen::AngleAxisd(kPi * u(rng), Eigen::Vector3d::UnitZ()))
                        .matrix();
    X_VN.translation() = 0.9 * r * Eigen::Vector3d(u(rng), u(rng), u(rng));
    arc.X_WN = torus.X_WV * X_VN;
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(arc, torus);
    const bool at_end = exact.s_rad == 0 || exact.s_rad == arc.sweep_rad;
    if (!at_end || exact.contact || exact.clearance_m > 0.2 * r) continue;
    ++checked;
    const ArcTorusClearance mesh = model.Calc(arc.X_WN, torus.X_WV);
    ASSERT_EQ(mesh.status, ClearanceStatus::kOk);
    EXPECT_NEAR(mesh.clearance_m, exact.clearance_m, sagittas) << i;
  }
  EXPECT_EQ(checked, 40);
}

}  // namespace
}  // namespace microdex::geometry
