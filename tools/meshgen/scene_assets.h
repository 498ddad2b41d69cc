#pragma once
// The training scenes' mesh assets (assets/meshes/): each file's name, what it is for, and the
// generator call that makes it. microdex-meshgen writes them; a test regenerates each and
// compares it with the committed file, so the table and the files cannot drift apart.

#include <functional>
#include <string>
#include <vector>

#include "common/mesh/triangle_mesh.h"

namespace microdex::meshgen {

struct SceneAsset {
  std::string file;     // name in assets/meshes/; the extension picks the format
  std::string purpose;  // the scene and the role (view or collision geometry), one line
  std::function<mesh::TriangleMesh()> make;
};

const std::vector<SceneAsset>& SceneAssets();

}  // namespace microdex::meshgen
