#pragma once
// A station's scene as files, so that a remote instructor mirrors it without having them: the
// scene file (YAML) and every file it names (the thread's and tissue's parameter files, the
// visuals' meshes), each by its path relative to their common folder. The station publishes
// them once on the SceneDescription topic (idl/scene_description.idl) and their hash in its
// StationInfo (scene_hash); the instructor checks what it received (CheckSceneFiles), writes
// the files under a folder of its own (WriteSceneFiles) and loads the scene from there with the
// same loader as the station (scene::LoadScene), so both draw the same scene.
//
// The hash is XXH3-64 over every file in order: its path, a NUL, its size (u64, little-endian)
// and its bytes; the scene path first (it names which file is the scene).

#include <cstdint>
#include <string>
#include <vector>

#include "common/scene/scene.h"

namespace microdex::view {

// Limits a received description must keep (a station's real scene uses a few hundred KiB).
inline constexpr std::size_t kMaxSceneFiles = 32;
inline constexpr std::size_t kMaxSceneFileBytes = std::size_t{4} << 20;    // 4 MiB each
inline constexpr std::size_t kMaxSceneTotalBytes = std::size_t{16} << 20;  // 16 MiB in all
inline constexpr std::size_t kMaxScenePathLength = 200;

struct SceneFile {
  std::string path;  // relative, '/'-separated
  std::string bytes;
};

struct SceneFiles {
  std::string scene_path;  // which of the files is the scene
  std::vector<SceneFile> files;
  std::uint64_t hash = 0;
};

// The files of a scene loaded from a file (scene.path must name it). Throws
// std::runtime_error naming a file that cannot be read, or std::invalid_argument when the
// scene was not loaded from a file or a description would exceed the limits.
SceneFiles CollectSceneFiles(const scene::SceneModel& scene);

// The hash of the files as described above.
std::uint64_t HashSceneFiles(const std::string& scene_path, const std::vector<SceneFile>& files);

// "" when `d` is sound: within the limits, every path relative without "." or ".." parts or
// characters outside [A-Za-z0-9._-/], no path twice, the scene among the files, and d.hash
// equal to the files' hash; else the first problem, naming the file.
std::string CheckSceneFiles(const SceneFiles& d);

// Writes the files under `dir` (created) and returns the scene file's path there. Call only
// with a description CheckSceneFiles accepted. Throws std::runtime_error naming the file that
// could not be written.
std::string WriteSceneFiles(const SceneFiles& d, const std::string& dir);

// The hash as 16 hex digits (folder names, messages).
std::string HashHex(std::uint64_t hash);

}  // namespace microdex::view
