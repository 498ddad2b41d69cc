// microdex-meshgen: writes the training scenes' mesh assets (scene_assets.cc) into a folder.
//
//   microdex-meshgen --out assets/meshes            all of them
//   microdex-meshgen --out /tmp/m --only wire_course.obj
//   microdex-meshgen --list                         names and purposes
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "common/mesh/mesh_io.h"
#include "tools/meshgen/scene_assets.h"

namespace {

// Writes the assets; bad arguments exit 2, a failed write 1.
int Run(int argc, char** argv) {
  CLI::App app{"microdex-meshgen: writes the training scenes' mesh assets (metres)"};
  std::string out;
  std::vector<std::string> only;
  bool list = false;
  app.add_option("--out", out, "output folder (created when missing), e.g. assets/meshes");
  app.add_option("--only", only, "write only these files (names as --list prints them)");
  app.add_flag("--list", list, "print the asset names and purposes, write nothing");
  CLI11_PARSE(app, argc, argv);
  const auto& assets = microdex::meshgen::SceneAssets();
  if (list) {
    for (const auto& a : assets) std::printf("%-30s %s\n", a.file.c_str(), a.purpose.c_str());
    return 0;
  }
  if (out.empty()) {
    std::fprintf(stderr, "microdex-meshgen: --out is required (or --list)\n");
    return 2;
  }
  for (const std::string& name : only) {
    if (std::none_of(assets.begin(), assets.end(), [&](const auto& a) { return a.file == name; })) {
      std::fprintf(stderr, "microdex-meshgen: --only: unknown asset '%s' (see --list)\n",
                   name.c_str());
      return 2;
    }
  }
  std::filesystem::create_directories(out);
  for (const auto& a : assets) {
    if (!only.empty() && std::find(only.begin(), only.end(), a.file) == only.end()) continue;
    const microdex::mesh::TriangleMesh mesh = a.make();
    const std::string path = (std::filesystem::path(out) / a.file).string();
    microdex::mesh::SaveMesh(mesh, path);
    std::printf("%-30s %6zu vertices %6zu triangles %8ju bytes\n", a.file.c_str(),
                mesh.vertices.size(), mesh.triangles.size(),
                static_cast<std::uintmax_t>(std::filesystem::file_size(path)));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-meshgen: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "microdex-meshgen: unknown error\n");
  }
  return 1;
}
