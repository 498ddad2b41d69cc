// The committed scene assets are what the generator table makes: each regenerated asset,
// written and read back in its own format, matches the committed file read the same way.
#include "tools/meshgen/scene_assets.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "common/mesh/mesh_io.h"

namespace microdex::meshgen {
namespace {

// Both go through the same float conversion: equal up to the printing of OBJ text.
constexpr double kAssetTol_m = 1e-9;

TEST(MeshSceneAssets, CommittedFilesMatchTheGenerators) {
  const std::filesystem::path dir = MICRODEX_MESH_ASSET_DIR;
  std::set<std::string> names;
  for (const SceneAsset& asset : SceneAssets()) {
    SCOPED_TRACE(asset.file);
    EXPECT_TRUE(names.insert(asset.file).second) << "listed twice";
    const mesh::TriangleMesh committed = mesh::LoadMesh((dir / asset.file).string());
    const std::string fresh_path = ::testing::TempDir() + "/regenerated_" + asset.file;
    mesh::SaveMesh(asset.make(), fresh_path);
    const mesh::TriangleMesh fresh = mesh::LoadMesh(fresh_path);
    ASSERT_EQ(committed.triangles.size(), fresh.triangles.size());
    ASSERT_EQ(committed.vertices.size(), fresh.vertices.size());
    double worst = 0;
    for (size_t t = 0; t < fresh.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        worst = std::max(worst, (committed.vertices[committed.triangles[t][k]] -
                                 fresh.vertices[fresh.triangles[t][k]])
                                    .norm());
      }
    }
    EXPECT_LE(worst, kAssetTol_m);
  }
}

TEST(MeshSceneAssets, ClosedWhereTheyAreSolids) {
  // Every asset is a closed surface (the loop and the jaw pairs as closed parts).
  for (const SceneAsset& asset : SceneAssets()) {
    EXPECT_TRUE(mesh::CalcEdgeTopology(asset.make()).closed()) << asset.file;
    EXPECT_GT(mesh::CalcEnclosedVolume(asset.make()), 0) << asset.file;
  }
}

}  // namespace
}  // namespace microdex::meshgen
