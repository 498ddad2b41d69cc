// A scene as files (common/view/scene_files.h): collected with every file it names, checked
// (paths, sizes, hash), written elsewhere and loaded there to the same scene as the original.
#include "common/view/scene_files.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "common/scene/scene.h"
#include "common/view/scene_view.h"

namespace microdex::view {
namespace {

namespace fs = std::filesystem;

const SceneFile* Find(const SceneFiles& d, const std::string& path) {
  for (const SceneFile& f : d.files) {
    if (f.path == path) return &f;
  }
  return nullptr;
}

TEST(SceneFiles, CollectsTheSceneAndEveryFileItNames) {
  // Parameter file beside the scene, two meshes in ../meshes.
  const scene::SceneModel s = scene::LoadScene("assets/scenes/needle_through_tissue.yaml");
  const SceneFiles d = CollectSceneFiles(s);
  EXPECT_EQ(d.scene_path, "scenes/needle_through_tissue.yaml");
  EXPECT_NE(Find(d, "scenes/tissue_skin_patch.yaml"), nullptr);
  EXPECT_NE(Find(d, "meshes/tissue_patch_20x20mm.obj"), nullptr);
  EXPECT_NE(Find(d, "meshes/curved_needle_3_8.obj"), nullptr);
  EXPECT_EQ(d.files.size(), 4u);
  EXPECT_EQ(d.hash, HashSceneFiles(d.scene_path, d.files));
  EXPECT_EQ(CheckSceneFiles(d), "");
}

TEST(SceneFiles, WrittenElsewhereLoadsTheSameScene) {
  const scene::SceneModel s = scene::LoadScene("assets/scenes/suture_on_tissue.yaml");
  const SceneFiles d = CollectSceneFiles(s);
  const fs::path dir =
      fs::temp_directory_path() / ("microdex-scene-files-test-" + std::to_string(getpid()));
  const std::string path = WriteSceneFiles(d, dir.string());
  const scene::SceneModel copy = scene::LoadScene(path);
  EXPECT_EQ(SceneViewJson(copy), SceneViewJson(s));
  fs::remove_all(dir);
}

TEST(SceneFiles, RefusesABadDescriptionNamingTheProblem) {
  const SceneFiles good = CollectSceneFiles(scene::LoadScene("assets/scenes/tremor_hold.yaml"));
  ASSERT_EQ(CheckSceneFiles(good), "");

  SceneFiles changed = good;
  changed.files.back().bytes += ' ';  // a byte more than the hash covers
  EXPECT_NE(CheckSceneFiles(changed).find("hash"), std::string::npos);

  for (const std::string bad : {"../etc/passwd", "/etc/passwd", "a//b", "a/./b", "a b", ""}) {
    SceneFiles d = good;
    d.files.front().path = bad;
    d.scene_path = bad;
    d.hash = HashSceneFiles(d.scene_path, d.files);
    EXPECT_NE(CheckSceneFiles(d), "") << bad;
  }

  SceneFiles twice = good;
  twice.files.push_back(twice.files.front());
  twice.hash = HashSceneFiles(twice.scene_path, twice.files);
  EXPECT_NE(CheckSceneFiles(twice).find("twice"), std::string::npos);

  SceneFiles missing = good;
  missing.scene_path = "scenes/other.yaml";
  missing.hash = HashSceneFiles(missing.scene_path, missing.files);
  EXPECT_NE(CheckSceneFiles(missing).find("not among"), std::string::npos);

  SceneFiles big = good;
  big.files.front().bytes.assign(kMaxSceneFileBytes + 1, 'x');
  big.hash = HashSceneFiles(big.scene_path, big.files);
  EXPECT_NE(CheckSceneFiles(big).find("bytes"), std::string::npos);

  SceneFiles many = good;
  for (std::size_t i = 0; many.files.size() <= kMaxSceneFiles; ++i) {
    many.files.push_back({"extra/" + std::to_string(i), "x"});
  }
  many.hash = HashSceneFiles(many.scene_path, many.files);
  EXPECT_NE(CheckSceneFiles(many).find("files"), std::string::npos);

  EXPECT_NE(CheckSceneFiles(SceneFiles{}), "");
}

TEST(SceneFiles, TheHashCoversPathsAndContents) {
  const std::vector<SceneFile> a{{"s.yaml", "name: x"}, {"m.obj", "v 0 0 0"}};
  std::vector<SceneFile> b = a;
  b[1].path = "n.obj";
  std::vector<SceneFile> c = a;
  c[1].bytes = "v 0 0 1";
  EXPECT_NE(HashSceneFiles("s.yaml", a), HashSceneFiles("s.yaml", b));
  EXPECT_NE(HashSceneFiles("s.yaml", a), HashSceneFiles("s.yaml", c));
  EXPECT_NE(HashSceneFiles("s.yaml", a), HashSceneFiles("m.obj", a));
  EXPECT_EQ(HashSceneFiles("s.yaml", a), HashSceneFiles("s.yaml", a));
}

TEST(SceneFiles, ASceneFromTextHasNoFiles) {
  scene::SceneModel s;
  EXPECT_THROW(CollectSceneFiles(s), std::invalid_argument);
}

}  // namespace
}  // namespace microdex::view
