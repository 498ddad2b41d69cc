#pragma once
// Baseline of the loop-along-a-wire clearance (loop_wire.h), for the benchmark and the
// tests' peer check: triangle meshes of the two solids and FCL's distance (as the needle's
// mesh baseline, arc_torus_mesh.h).
//
// The loop is the torus wall (MakeTorusWallMesh, n_major × n_minor quads), the wire a
// tube of n_around quads around each ring, rings every 2π/n_major of turn on arcs and at the
// two ends of segments (inscribed polygons, no end caps). Both BVHs are built in units of R
// (FCL's triangle distance has an absolute threshold that millimetre facets fall below). FCL's
// mesh distance D is unsigned and gives no depth once the meshes intersect: D > 0 → clearance
// D, no contact; D ≤ 0 → contact, clearance reported as 0. The meshes are inscribed, so D
// overestimates the clearance by up to the sagittas; a wire that lies wholly inside the loop's
// wire (or the reverse) is not seen.

#include <memory>

#include "common/geometry/loop_wire.h"

namespace microdex::geometry {

struct LoopWireMeshResolution {
  int n_major = 64;   // quads around the loop's circle; rings per turn of a wire arc
  int n_minor = 16;   // quads around the loop's wire
  int n_around = 16;  // quads around the course's wire
};

class LoopWireMeshModel {
 public:
  LoopWireMeshModel(const LoopWireModel& model, const LoopWireMeshResolution& resolution);
  ~LoopWireMeshModel();
  LoopWireMeshModel(const LoopWireMeshModel&) = delete;
  LoopWireMeshModel& operator=(const LoopWireMeshModel&) = delete;

  // Allocates (FCL's traversal): not for the haptic loop.
  LoopWireClearance Calc(const Eigen::Isometry3d& X_WL) const;
  int num_triangles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace microdex::geometry
