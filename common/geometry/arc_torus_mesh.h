#pragma once
// Baseline (thesis Fig. 4.3a, the modern equivalent of RAPID): the needle and the vessel wall
// as triangle meshes, their distance by FCL (OBBRSS bounding-volume hierarchies).
//
// The needle is a ribbon of `segments` quads along the inscribed polyline of the arc, of
// negligible width across the needle plane; the wall is the torus segment's surface with
// n_major × n_minor quads (no end caps: the clearance ignores points outside the azimuth
// range; common/mesh's MakeTorusTubeMesh without caps). Meshes are OBJ files in assets/meshes/,
// written when missing and always loaded through common/mesh's LoadMesh (assimp), so the method
// runs on exactly what an asset pipeline would give it. The files are in metres; the BVHs
// (common/mesh/mesh_fcl.h) are built in units of R and queried in the vessel frame (FCL's
// triangle distance has an absolute threshold that millimetre-scale facets fall below).
//
// The mesh "clearance" (README.md, "Mesh baseline"): FCL's mesh–mesh distance D is unsigned
// and gives no depth once the meshes intersect, so
//   meshes intersect (D ≤ 0)          → contact, clearance reported as 0;
//   disjoint, needle inside the tube  → clearance = +D;
//   disjoint, needle outside the tube → clearance = −D,
// where inside/outside is decided by the needle's first vertex against the analytic torus.
// This is the method's own answer; its error against the exact clearance is measured by the
// benchmark over the queries where it reports no contact, and its contact flag over all.

#include <memory>
#include <string>
#include <vector>

#include "common/geometry/arc_torus.h"
#include "common/mesh/triangle_mesh.h"

namespace microdex::geometry {

// In the needle frame N: ribbon along the polyline (ρ cos s_i, ρ sin s_i, ±half_width).
mesh::TriangleMesh MakeNeedleRibbonMesh(double radius_m, double sweep_rad, int segments,
                                        double half_width_m);

struct MeshResolution {
  int needle_segments = 32;
  int n_major = 64;  // quads around the core circle over a full turn (scaled by Ω / 2π)
  int n_minor = 16;  // quads around the tube
};

// The two meshes of one needle–vessel geometry (poses excluded), their BVHs built once.
class ArcTorusMeshModel {
 public:
  // Loads `dir`/needle_ribbon_….obj and `dir`/vessel_wall_….obj (names carry the geometry
  // and resolution), writing them first when missing. Throws microdex::InputError for an
  // unreadable or invalid file.
  ArcTorusMeshModel(const ArcDef& arc, const TorusSegmentDef& torus,
                    const MeshResolution& resolution, const std::string& dir);
  ~ArcTorusMeshModel();
  ArcTorusMeshModel(const ArcTorusMeshModel&) = delete;
  ArcTorusMeshModel& operator=(const ArcTorusMeshModel&) = delete;

  // The mesh clearance for these poses (the radii and angles are the model's).
  ArcTorusClearance Calc(const Eigen::Isometry3d& X_WN, const Eigen::Isometry3d& X_WV) const;

  int num_triangles() const;
  const std::string& needle_path() const { return needle_path_; }
  const std::string& vessel_path() const { return vessel_path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string needle_path_, vessel_path_;
};

}  // namespace microdex::geometry
