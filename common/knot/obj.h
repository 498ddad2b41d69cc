#pragma once
// Thread polylines in Wavefront OBJ: `v x y z` vertices and one `l` element (or several
// that chain end to end) listing the thread's nodes in order.

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace microdex::knot {

// OBJ has no field for a thread's diameter; it travels as a comment line of its own,
// `# thread_diameter_m D` (metres), so that the stitch-knot recogniser reads a knot with the
// thread's diameter instead of taking it from the link length (StitchKnotOptions).

// Reads the polyline of `path`, and into `thread_diameter_m` (if given) the file's thread
// diameter, 0 when it has none. Throws std::runtime_error "PATH:LINE: reason" (or "PATH:
// reason" when no line is to blame) for a missing file, a malformed vertex or index, an
// index out of range, no `l` element, `l` elements that do not chain into one path, or a
// thread diameter that is not a positive finite number.
std::vector<Eigen::Vector3d> ReadObjPolyline(const std::filesystem::path& path,
                                             double* thread_diameter_m = nullptr);

// Writes `nodes` as vertices and one `l` element; `comment` lines are written first with
// a leading "# ", then the thread diameter's line when thread_diameter_m > 0. Throws
// std::runtime_error if the file cannot be written.
void WriteObjPolyline(const std::filesystem::path& path, std::span<const Eigen::Vector3d> nodes,
                      const std::vector<std::string>& comment = {}, double thread_diameter_m = 0.0);

}  // namespace microdex::knot
