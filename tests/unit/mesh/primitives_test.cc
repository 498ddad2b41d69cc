// The generators against analytic facts: vertices on the analytic surface, closed and
// consistently oriented surfaces, volumes and areas exact where the polyhedron's are known in
// closed form, and converging to the smooth shape's as the resolution doubles otherwise.
#include "common/mesh/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace microdex::mesh {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kRelTol = 1e-12;  // round-off of sums over a few thousand facets

// Relative errors of `measure` at a resolution and at twice it: the second about a quarter of
// the first (inscribed facets: error ∝ h²); between 1/6 and 1/3 allowed for the finite sizes.
template <typename Measure>
void ExpectSecondOrder(const Measure& measure_at, double exact, const char* what) {
  const double e1 = std::abs(measure_at(1) - exact) / exact;
  const double e2 = std::abs(measure_at(2) - exact) / exact;
  EXPECT_GT(e1, 0) << what;
  EXPECT_LT(e1, 0.1) << what;
  EXPECT_LT(e2, e1 / 3) << what;
  EXPECT_GT(e2, e1 / 6) << what;
}

TEST(MeshPrimitives, TorusVerticesAtTheTubeRadiusFromTheCoreCircle) {
  const TorusTubeMeshDef def{.core_radius_m = 5e-3,
                             .tube_radius_m = 0.5e-3,
                             .segment_angle_rad = 1.5 * kPi,
                             .n_major = 24,
                             .n_minor = 10,
                             .end_caps = false};
  const TriangleMesh mesh = MakeTorusTubeMesh(def);
  ASSERT_EQ(mesh.vertices.size(), 25u * 10u);
  for (const Eigen::Vector3d& p : mesh.vertices) {
    const double d = std::hypot(std::hypot(p.x(), p.y()) - def.core_radius_m, p.z());
    EXPECT_NEAR(d, def.tube_radius_m, 1e-15);
    // Azimuth inside [0, Ω].
    const double phi = std::atan2(p.y(), p.x());
    EXPECT_LE(phi < -1e-12 ? phi + 2 * kPi : phi, def.segment_angle_rad + 1e-12);
  }
  // An open segment: its two end rings are the boundary.
  const EdgeTopology open = CalcEdgeTopology(mesh);
  EXPECT_EQ(open.boundary_edges, 2 * def.n_minor);
  EXPECT_EQ(open.non_manifold_edges + open.inconsistent_edges + open.degenerate_triangles, 0);
  TorusTubeMeshDef capped = def;
  capped.end_caps = true;
  EXPECT_TRUE(CalcEdgeTopology(MakeTorusTubeMesh(capped)).closed());
  EXPECT_TRUE(CalcEdgeTopology(MakeTorusTubeMesh({})).closed());  // full turn
}

TEST(MeshPrimitives, TorusVolumeAndAreaConverge) {
  const double R = 5e-3, r = 0.5e-3;
  for (const double omega : {2 * kPi, 0.75 * kPi}) {
    const auto mesh_at = [&](int k) {
      return MakeTorusTubeMesh({.core_radius_m = R,
                                .tube_radius_m = r,
                                .segment_angle_rad = omega,
                                .n_major = 32 * k,
                                .n_minor = 12 * k,
                                .end_caps = true});
    };
    // Pappus: the disc of area πr² swept along the core arc Rω; the wall without the caps
    // 2πr · Rω (the caps' area added for a segment).
    const bool full = omega == 2 * kPi;
    ExpectSecondOrder([&](int k) { return CalcEnclosedVolume(mesh_at(k)); },
                      kPi * r * r * R * omega, "torus volume");
    ExpectSecondOrder([&](int k) { return CalcSurfaceArea(mesh_at(k)); },
                      2 * kPi * r * R * omega + (full ? 0 : 2 * kPi * r * r), "torus area");
  }
}

TEST(MeshPrimitives, CylinderIsThePrismOfTheInscribedPolygon) {
  const CylinderMeshDef def{.radius_m = 0.4e-3, .length_m = 1.5e-3, .n_around = 17};
  const TriangleMesh mesh = MakeCylinderMesh(def);
  EXPECT_TRUE(CalcEdgeTopology(mesh).closed());
  const int n = def.n_around;
  const double r = def.radius_m, L = def.length_m;
  const double polygon_area = 0.5 * n * std::sin(2 * kPi / n) * r * r;
  const double polygon_perimeter = 2 * n * r * std::sin(kPi / n);
  EXPECT_NEAR(CalcEnclosedVolume(mesh), polygon_area * L, kRelTol * r * r * L);
  EXPECT_NEAR(CalcSurfaceArea(mesh), polygon_perimeter * L + 2 * polygon_area, kRelTol * r * L);
  const Aabb box = CalcBoundingBox(mesh);
  EXPECT_NEAR(box.min.z(), -L / 2, 1e-18);
  EXPECT_NEAR(box.max.z(), L / 2, 1e-18);
  ExpectSecondOrder(
      [&](int k) {
        return CalcEnclosedVolume(
            MakeCylinderMesh({.radius_m = r, .length_m = L, .n_around = 16 * k}));
      },
      kPi * r * r * L, "cylinder volume");
}

TEST(MeshPrimitives, BoxAndSlabAreExact) {
  const Eigen::Vector3d size(1e-3, 2e-3, 0.5e-3);
  const TriangleMesh box = MakeBoxMesh({.size_m = size});
  EXPECT_EQ(box.triangles.size(), 12u);
  EXPECT_TRUE(CalcEdgeTopology(box).closed());
  EXPECT_NEAR(CalcEnclosedVolume(box), size.prod(), kRelTol * size.prod());
  const double box_area = 2 * (size.x() * size.y() + size.y() * size.z() + size.x() * size.z());
  EXPECT_NEAR(CalcSurfaceArea(box), box_area, kRelTol * box_area);

  const TissueSlabMeshDef slab{
      .size_x_m = 20e-3, .size_y_m = 15e-3, .thickness_m = 2e-3, .nx = 7, .ny = 5};
  const TriangleMesh tissue = MakeTissueSlabMesh(slab);
  EXPECT_TRUE(CalcEdgeTopology(tissue).closed());
  const double volume = slab.size_x_m * slab.size_y_m * slab.thickness_m;
  EXPECT_NEAR(CalcEnclosedVolume(tissue), volume, kRelTol * volume);
  const double area =
      2 * slab.size_x_m * slab.size_y_m + 2 * (slab.size_x_m + slab.size_y_m) * slab.thickness_m;
  EXPECT_NEAR(CalcSurfaceArea(tissue), area, kRelTol * area);
  // The documented layout of the top grid: vertex (i, j) at i + (nx + 1) j.
  for (int j = 0; j <= slab.ny; ++j) {
    for (int i = 0; i <= slab.nx; ++i) {
      const Eigen::Vector3d& p = tissue.vertices[i + (slab.nx + 1) * j];
      EXPECT_NEAR(p.x(), slab.size_x_m * (double(i) / slab.nx - 0.5), 1e-18);
      EXPECT_NEAR(p.y(), slab.size_y_m * (double(j) / slab.ny - 0.5), 1e-18);
      EXPECT_EQ(p.z(), 0);
    }
  }
}

TEST(MeshPrimitives, SphereOnItsRadiusAndConverging) {
  const SphereMeshDef def{.radius_m = 0.5e-3, .n_lat = 9, .n_lon = 14};
  const TriangleMesh mesh = MakeSphereMesh(def);
  EXPECT_TRUE(CalcEdgeTopology(mesh).closed());
  EXPECT_EQ(mesh.vertices.size(), 2u + 8u * 14u);
  for (const Eigen::Vector3d& p : mesh.vertices) EXPECT_NEAR(p.norm(), def.radius_m, 1e-18);
  const double R = def.radius_m;
  const auto mesh_at = [&](int k) {
    return MakeSphereMesh({.radius_m = R, .n_lat = 12 * k, .n_lon = 24 * k});
  };
  ExpectSecondOrder([&](int k) { return CalcEnclosedVolume(mesh_at(k)); }, 4 * kPi * R * R * R / 3,
                    "sphere volume");
  ExpectSecondOrder([&](int k) { return CalcSurfaceArea(mesh_at(k)); }, 4 * kPi * R * R,
                    "sphere area");
}

TEST(MeshPrimitives, VesselIsTheAnnularPrismUpToTheCut) {
  for (const double cut : {0.0, 0.6}) {
    const VesselCylinderMeshDef def{.outer_radius_m = 0.5e-3,
                                    .wall_thickness_m = 0.1e-3,
                                    .length_m = 6e-3,
                                    .cut_angle_rad = cut,
                                    .n_around = 20,
                                    .n_along = 5};
    const TriangleMesh mesh = MakeVesselCylinderMesh(def);
    EXPECT_TRUE(CalcEdgeTopology(mesh).closed()) << cut;
    // Between z = 0 and a plane through (0, 0, length): the annulus polygon's area times the
    // length, whatever the plane's tilt (the polygon's first moment about the axis is zero).
    const double ro = def.outer_radius_m, ri = ro - def.wall_thickness_m;
    const double annulus =
        0.5 * def.n_around * std::sin(2 * kPi / def.n_around) * (ro * ro - ri * ri);
    EXPECT_NEAR(CalcEnclosedVolume(mesh), annulus * def.length_m, kRelTol * ro * ro * def.length_m)
        << cut;
    for (const Eigen::Vector3d& p : mesh.vertices) {
      const double rho = std::hypot(p.x(), p.y());
      EXPECT_TRUE(std::abs(rho - ro) < 1e-18 || std::abs(rho - ri) < 1e-18);
      EXPECT_GE(p.z(), 0);
      EXPECT_LE(p.z(), def.length_m + p.x() * std::tan(cut) + 1e-18);
    }
  }
}

TEST(MeshPrimitives, WireFollowsItsSectionsAndHasPappusVolume) {
  // A straight 4 mm, then a quarter turn of radius 3 mm towards +y (N), then one towards +z
  // (B): the end is at (4 + 3, 3, 0) + 3 (0, 1, 1) heading +z.
  WireMeshDef def;
  def.wire_radius_m = 0.2e-3;
  def.sections = {
      {.length_m = 4e-3},
      {.length_m = 3e-3 * kPi / 2, .bend_radius_m = 3e-3, .bend_direction_rad = 0},
      {.length_m = 3e-3 * kPi / 2, .bend_radius_m = 3e-3, .bend_direction_rad = kPi / 2}};
  const Eigen::Isometry3d X_PE = CalcWireEndPose(def);
  EXPECT_LT((X_PE.translation() - Eigen::Vector3d(7e-3, 6e-3, 3e-3)).norm(), 1e-17);
  EXPECT_LT((X_PE.linear().col(0) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_NEAR(X_PE.linear().determinant(), 1, 1e-15);
  EXPECT_TRUE(CalcEdgeTopology(MakeWireMesh(def)).closed());
  double length = 0;
  for (const WireSectionDef& s : def.sections) length += s.length_m;
  const double r = def.wire_radius_m;
  ExpectSecondOrder(
      [&](int k) {
        WireMeshDef d = def;
        d.max_arc_step_rad = kPi / (8 * k);
        d.n_around = 10 * k;
        return CalcEnclosedVolume(MakeWireMesh(d));
      },
      kPi * r * r * length, "wire volume");
}

TEST(MeshPrimitives, NeedleTapersToItsTip) {
  const NeedleMeshDef def{};
  const TriangleMesh mesh = MakeNeedleMesh(def);
  EXPECT_TRUE(CalcEdgeTopology(mesh).closed());
  const double rho = def.arc_radius_m, S = def.sweep_rad, r = def.wire_radius_m;
  // The tip is one vertex, on the centre line at s = S.
  const Eigen::Vector3d tip(rho * std::cos(S), rho * std::sin(S), 0);
  int at_tip = 0;
  for (const Eigen::Vector3d& p : mesh.vertices) {
    at_tip += (p - tip).norm() < 1e-18;
    // Within the wire radius of the centre circle.
    EXPECT_LE(std::hypot(std::hypot(p.x(), p.y()) - rho, p.z()), r + 1e-17);  // ulps of ρ
  }
  EXPECT_EQ(at_tip, 1);
  // A disc of radius r(s) swept along the arc: π r² ρ ds, a cone over the taper.
  const double Lt = def.taper_length_m;
  ExpectSecondOrder(
      [&](int k) {
        NeedleMeshDef d = def;
        d.n_along = 48 * k;
        d.n_around = 12 * k;
        return CalcEnclosedVolume(MakeNeedleMesh(d));
      },
      kPi * r * r * (rho * S - Lt) + kPi * r * r * Lt / 3, "needle volume");
}

TEST(MeshPrimitives, JawIsAFrustumAndThePairOpens) {
  const JawMeshDef def{};
  const TriangleMesh jaw = MakeJawMesh(def);
  EXPECT_TRUE(CalcEdgeTopology(jaw).closed());
  // The cross-section: a polygon inscribed in a half ellipse, n triangles from the middle of
  // the inner face of area (h · w/2 · sin(π/n)) / 2 each; a frustum of it.
  const int n = def.n_back;
  const double section = 0.25 * n * def.height_m * def.width_m * std::sin(kPi / n);
  const double t = def.tip_scale;
  const double volume = section * def.length_m * (1 + t + t * t) / 3;
  EXPECT_NEAR(CalcEnclosedVolume(jaw), volume, kRelTol * volume);
  for (const Eigen::Vector3d& p : jaw.vertices) EXPECT_GE(p.y(), 0);  // the back is at +y

  const double opening = 0.4;
  const TriangleMesh pair = MakeJawPairMesh(def, opening);
  EXPECT_TRUE(CalcEdgeTopology(pair).closed());
  EXPECT_NEAR(CalcEnclosedVolume(pair), 2 * volume, kRelTol * volume);
  // The upper jaw on the far side of its turned inner face, the lower one on the near side of
  // its own.
  const size_t half = jaw.vertices.size();
  for (size_t v = 0; v < pair.vertices.size(); ++v) {
    const Eigen::Vector3d& p = pair.vertices[v];
    const int side = v < half ? 1 : -1;
    const double a = side * opening / 2;
    EXPECT_GE(side * (-std::sin(a) * p.x() + std::cos(a) * p.y()), -1e-18) << v;
  }
  EXPECT_THROW(MakeJawPairMesh(def, -0.1), std::invalid_argument);
}

TEST(MeshPrimitives, LoopIsTwoClosedParts) {
  const LoopMeshDef def{};
  const TriangleMesh mesh = MakeLoopMesh(def);
  EXPECT_TRUE(CalcEdgeTopology(mesh).closed());
  const Aabb box = CalcBoundingBox(mesh);
  EXPECT_NEAR(box.max.x(), def.ring_radius_m + def.wire_radius_m, 1e-18);
  EXPECT_NEAR(box.min.x(), -def.ring_radius_m - def.handle_length_m, 1e-18);
  EXPECT_NEAR(box.max.z(), std::max(def.wire_radius_m, def.handle_radius_m), 1e-18);
}

TEST(MeshPrimitives, ValidateNamesTheField) {
  const auto message = [](const auto& make) -> std::string {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_EQ(message([] {
              MakeTorusTubeMesh({.tube_radius_m = 6e-3});
            }).rfind("TorusTubeMeshDef.tube_radius_m:", 0),
            0u);
  EXPECT_EQ(message([] {
              MakeSphereMesh({.radius_m = std::nan("")});
            }).rfind("SphereMeshDef.radius_m:", 0),
            0u);
  EXPECT_EQ(
      message([] { MakeCylinderMesh({.n_around = 2}); }).rfind("CylinderMeshDef.n_around:", 0), 0u);
  EXPECT_EQ(message([] {
              MakeNeedleMesh({.taper_length_m = 1.0});
            }).rfind("NeedleMeshDef.taper_length_m:", 0),
            0u);
  WireMeshDef wire;
  wire.sections[1].bend_radius_m = 0.1e-3;  // tighter than the wire is thick
  EXPECT_EQ(message([&] { MakeWireMesh(wire); }).rfind("WireMeshDef.sections[1].bend_radius_m:", 0),
            0u);
  EXPECT_EQ(message([] {
              MakeVesselCylinderMesh({.wall_thickness_m = 0.5e-3});
            }).rfind("VesselCylinderMeshDef.wall_thickness_m:", 0),
            0u);
}

}  // namespace
}  // namespace microdex::mesh
