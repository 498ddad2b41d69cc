#include "common/view/scene_files.h"

#include <xxhash.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <stdexcept>

namespace microdex::view {
namespace {

namespace fs = std::filesystem;

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot be read (scene description)");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path.string() + ": read error (scene description)");
  return bytes;
}

// The deepest folder holding every path.
fs::path CommonFolder(const std::vector<fs::path>& paths) {
  fs::path common = paths.front().parent_path();
  for (const fs::path& p : paths) {
    const fs::path dir = p.parent_path();
    fs::path shared;
    auto a = common.begin();
    auto b = dir.begin();
    for (; a != common.end() && b != dir.end() && *a == *b; ++a, ++b) shared /= *a;
    common = shared;
  }
  return common;
}

bool PathCharOk(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '_' || c == '-' || c == '/';
}

// "" or why `path` may not be written under a folder.
std::string CheckRelativePath(const std::string& path) {
  if (path.empty()) return "empty path";
  if (path.size() > kMaxScenePathLength) {
    return "path longer than " + std::to_string(kMaxScenePathLength) + " characters";
  }
  if (!std::all_of(path.begin(), path.end(), PathCharOk)) {
    return "path '" + path + "' has characters outside [A-Za-z0-9._-/]";
  }
  if (path.front() == '/') return "path '" + path + "' is absolute";
  std::istringstream parts(path);
  std::string part;
  while (std::getline(parts, part, '/')) {
    if (part.empty() || part == "." || part == "..") {
      return "path '" + path + "' has an empty, '.' or '..' part";
    }
  }
  if (path.back() == '/') return "path '" + path + "' names a folder";
  return "";
}

}  // namespace

std::string HashHex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

std::uint64_t HashSceneFiles(const std::string& scene_path, const std::vector<SceneFile>& files) {
  XXH3_state_t* state = XXH3_createState();
  if (state == nullptr) throw std::bad_alloc();
  XXH3_64bits_reset(state);
  XXH3_64bits_update(state, scene_path.data(), scene_path.size());
  const char nul = '\0';
  XXH3_64bits_update(state, &nul, 1);
  for (const SceneFile& f : files) {
    XXH3_64bits_update(state, f.path.data(), f.path.size());
    XXH3_64bits_update(state, &nul, 1);
    std::uint8_t size[8];
    const std::uint64_t n = f.bytes.size();
    for (int i = 0; i < 8; ++i) size[i] = static_cast<std::uint8_t>(n >> (8 * i));
    XXH3_64bits_update(state, size, sizeof size);
    XXH3_64bits_update(state, f.bytes.data(), f.bytes.size());
  }
  const std::uint64_t hash = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return hash;
}

SceneFiles CollectSceneFiles(const scene::SceneModel& s) {
  if (s.path.empty()) {
    throw std::invalid_argument("scene description: the scene was not loaded from a file");
  }
  std::vector<fs::path> paths{fs::weakly_canonical(s.path)};
  auto add = [&](const std::string& p) {
    if (p.empty()) return;
    const fs::path c = fs::weakly_canonical(p);
    if (std::find(paths.begin(), paths.end(), c) == paths.end()) paths.push_back(c);
  };
  if (s.thread) add(s.thread->params_path);
  if (s.tissue) add(s.tissue->params_path);
  for (const scene::VisualDef& v : s.visuals) add(v.mesh_path);
  const fs::path root = CommonFolder(paths);
  SceneFiles d;
  std::size_t total = 0;
  for (const fs::path& p : paths) {
    SceneFile f{p.lexically_relative(root).generic_string(), ReadAll(p)};
    if (const std::string why = CheckRelativePath(f.path); !why.empty()) {
      throw std::invalid_argument("scene description: " + p.string() + ": " + why);
    }
    if (f.bytes.size() > kMaxSceneFileBytes) {
      throw std::invalid_argument("scene description: " + p.string() + " is larger than " +
                                  std::to_string(kMaxSceneFileBytes) + " bytes");
    }
    total += f.bytes.size();
    d.files.push_back(std::move(f));
  }
  if (d.files.size() > kMaxSceneFiles || total > kMaxSceneTotalBytes) {
    throw std::invalid_argument("scene description: " + std::to_string(d.files.size()) +
                                " files of " + std::to_string(total) + " bytes exceed the limits");
  }
  d.scene_path = d.files.front().path;
  d.hash = HashSceneFiles(d.scene_path, d.files);
  return d;
}

std::string CheckSceneFiles(const SceneFiles& d) {
  if (d.files.empty()) return "no files";
  if (d.files.size() > kMaxSceneFiles) {
    return std::to_string(d.files.size()) + " files, more than " + std::to_string(kMaxSceneFiles);
  }
  std::size_t total = 0;
  std::set<std::string> seen;
  for (const SceneFile& f : d.files) {
    if (std::string why = CheckRelativePath(f.path); !why.empty()) return why;
    if (!seen.insert(f.path).second) return "path '" + f.path + "' twice";
    if (f.bytes.size() > kMaxSceneFileBytes) {
      return "file '" + f.path + "' is " + std::to_string(f.bytes.size()) + " bytes, more than " +
             std::to_string(kMaxSceneFileBytes);
    }
    total += f.bytes.size();
  }
  if (total > kMaxSceneTotalBytes) {
    return std::to_string(total) + " bytes in all, more than " +
           std::to_string(kMaxSceneTotalBytes);
  }
  if (seen.count(d.scene_path) == 0)
    return "the scene '" + d.scene_path + "' is not among the files";
  if (const std::uint64_t h = HashSceneFiles(d.scene_path, d.files); h != d.hash) {
    return "hash " + HashHex(h) + " of the files received differs from the hash sent " +
           HashHex(d.hash);
  }
  return "";
}

std::string WriteSceneFiles(const SceneFiles& d, const std::string& dir) {
  const fs::path root(dir);
  for (const SceneFile& f : d.files) {
    const fs::path p = root / f.path;
    std::error_code ec;
    fs::create_directories(p.parent_path(), ec);
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(f.bytes.data(), static_cast<std::streamsize>(f.bytes.size()));
    out.close();
    if (!out) throw std::runtime_error(p.string() + ": cannot be written (scene description)");
  }
  return (root / d.scene_path).string();
}

}  // namespace microdex::view
