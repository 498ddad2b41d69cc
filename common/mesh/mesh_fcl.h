#pragma once
// A mesh as FCL collision geometry (target microdex_mesh_fcl, so that microdex_mesh itself does
// not depend on FCL): an OBBRSS bounding-volume hierarchy for fcl::distance / fcl::collide.
//
// Scale: FCL's triangle–triangle distance (from PQP) tests the vertex–face case only where the
// squared length of a triangle's edge cross product exceeds 1e-15 — an absolute threshold, in
// length⁴. Millimetre-scale facets in metres fall below it, and their distances then come from
// edge pairs only, too large where a vertex faces a facet. Build the model with `length_scale`
// = 1 / (the scene's length, e.g. 1e3 for millimetre parts), place it with translations
// multiplied by the same factor, and divide the distances and points FCL returns by it.

#include <memory>

#include "common/mesh/triangle_mesh.h"
#include "fcl/geometry/bvh/BVH_model.h"

namespace microdex::mesh {

using FclMesh = fcl::BVHModel<fcl::OBBRSSd>;

// The hierarchy of the mesh with every vertex multiplied by length_scale (> 0, finite; throws
// std::invalid_argument naming it otherwise, or for a mesh with no triangles).
std::shared_ptr<FclMesh> MakeFclMesh(const TriangleMesh& mesh, double length_scale = 1.0);

}  // namespace microdex::mesh
