#pragma once
// Thread polylines in Wavefront OBJ: `v x y z` vertices and one `l` element (or several
// that chain end to end) listing the thread's nodes in order.

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace microdex::knot {

// Reads the polyline of `path`. Throws std::runtime_error "PATH:LINE: reason" (or "PATH:
// reason" when no line is to blame) for a missing file, a malformed vertex or index, an
// index out of range, no `l` element, or `l` elements that do not chain into one path.
std::vector<Eigen::Vector3d> ReadObjPolyline(const std::filesystem::path& path);

// Writes `nodes` as vertices and one `l` element; `comment` lines are written first with
// a leading "# ". Throws std::runtime_error if the file cannot be written.
void WriteObjPolyline(const std::filesystem::path& path, std::span<const Eigen::Vector3d> nodes,
                      const std::vector<std::string>& comment = {});

}  // namespace microdex::knot
