#pragma once
// Mesh generators for the training scenes' geometry. Lengths in metres, angles in radians; each
// Def has member defaults (the scenes' sizes) and one Validate() that throws
// std::invalid_argument("Def.field: expected …"); every generator validates its Def first.
//
// The meshes are inscribed: their vertices lie on the analytic surface, the facets inside it
// (so a mesh volume converges to the analytic one from below, with the square of the
// resolution). Every generator but MakeLoopMesh and MakeJawPairMesh (two closed parts each)
// gives one closed, consistently oriented surface (triangles counter-clockwise from outside),
// unless it says otherwise. No normals are generated: a view computes them (CalcVertexNormals,
// or flat shading for the box and the jaws).

#include <Eigen/Geometry>
#include <numbers>
#include <vector>

#include "common/mesh/triangle_mesh.h"

namespace microdex::mesh {

// A tube around a torus segment (the curved vessel of the needle scene; with a full turn, the
// target ring and the loop's ring). Frame V, as geometry::TorusSegmentDef: the core circle of
// radius R in the xy-plane around the origin, azimuth atan2(y, x) ∈ [0, Ω] from +x towards +y.
// Vertices (R + r cos ψ)(cos φ, sin φ, 0) + (0, 0, r sin ψ), ring by ring: φ = Ω i / n_major
// (i = 0…n_major, the last ring left out for a full turn), ψ = 2π j / n_minor; the triangles of
// the quad (i, j) are 2 (n_minor i + j) and the one after. Without end caps a segment is open
// (its wall only, the needle baseline's mesh).
struct TorusTubeMeshDef {
  double core_radius_m = 5e-3;                      // R > 0
  double tube_radius_m = 0.5e-3;                    // 0 < r < R
  double segment_angle_rad = 2 * std::numbers::pi;  // Ω ∈ (0, 2π]
  int n_major = 64;                                 // quads along the core over Ω, ≥ 1
  int n_minor = 16;                                 // quads around the tube, ≥ 3
  bool end_caps = true;  // flat discs close a segment's ends (none for a full turn)
  void Validate() const;
};
TriangleMesh MakeTorusTubeMesh(const TorusTubeMeshDef& def);

// A straight vessel with its lumen, cut open at one end (knot placement around a vessel's cut
// end). Frame C: the axis along +z, the vessel from the plane z = 0 to the cut plane
// z = length + x tan(cut_angle) (a bevelled cut for a non-zero angle); both ends are flat
// annuli, the lumen's wall faces the axis. Closed (the annular wall is the solid).
struct VesselCylinderMeshDef {
  double outer_radius_m = 0.5e-3;    // > 0
  double wall_thickness_m = 0.1e-3;  // ∈ (0, outer radius)
  double length_m = 6e-3;            // along the axis at x = 0, > outer_radius |tan(cut_angle)|
  double cut_angle_rad = 0;          // tilt of the cut plane about +y, |·| < π/2
  int n_around = 32;                 // ≥ 3
  int n_along = 12;                  // rings along the axis, ≥ 1
  void Validate() const;
};
TriangleMesh MakeVesselCylinderMesh(const VesselCylinderMeshDef& def);

// One section of a wire's centre line: straight (bend_radius_m = 0) or a circular arc.
struct WireSectionDef {
  double length_m = 5e-3;         // along the centre line (an arc's length is its radius × angle)
  double bend_radius_m = 0;       // 0: straight; else the arc's radius, > the wire radius
  double bend_direction_rad = 0;  // an arc bends towards cos(·) N + sin(·) B (see WireMeshDef)
};

// A tube along a path of straight and arc sections (the wire of "passing a loop along a wire").
// Frame P: the path starts at the origin heading +x, with the frame (T, N, B) = (+x, +y, +z)
// carried along the path without twist; an arc turns T by its angle towards its bend direction.
// Flat caps at both ends.
struct WireMeshDef {
  double wire_radius_m = 0.25e-3;                   // > 0
  std::vector<WireSectionDef> sections;             // at least one; defaults to an S-shaped course
  double max_arc_step_rad = std::numbers::pi / 32;  // arc rings at most this angle apart, > 0
  int n_around = 12;                                // ≥ 3
  WireMeshDef();
  void Validate() const;
};
TriangleMesh MakeWireMesh(const WireMeshDef& def);
// The end of the path: the pose of the frame (T, N, B) as the columns of the rotation, in P.
Eigen::Isometry3d CalcWireEndPose(const WireMeshDef& def);

// The loop of "passing a loop along a wire": a ring and a straight handle. Frame L: the ring's
// core circle of radius R in the xy-plane around the origin; the handle's axis along −x from the
// ring's core at (−R, 0, 0) to (−R − handle_length, 0, 0). Two closed parts that overlap where the
// handle enters the ring (CalcEnclosedVolume counts that overlap twice).
struct LoopMeshDef {
  double ring_radius_m = 1.5e-3;     // R, of the core circle, > wire radius
  double wire_radius_m = 0.1e-3;     // > 0
  double handle_length_m = 10e-3;    // > 0
  double handle_radius_m = 0.15e-3;  // > 0
  int n_major = 48;                  // ≥ 3
  int n_minor = 12;                  // ≥ 3
  void Validate() const;
};
TriangleMesh MakeLoopMesh(const LoopMeshDef& def);

// A curved suture needle: a round wire along an arc, flat at the tail, tapering to a point at the
// tip. Frame N, as geometry::ArcDef: the centre line (ρ cos s, ρ sin s, 0), s ∈ [0, S], the tail
// at s = 0, the tip at s = S; the wire radius falls linearly to 0 over the last taper_length
// (arc length) before the tip.
struct NeedleMeshDef {
  double arc_radius_m = 5e-3;                  // ρ > wire radius
  double sweep_rad = 0.75 * std::numbers::pi;  // S ∈ (0, 2π): 3/8 of a circle by default
  double wire_radius_m = 0.1e-3;               // > 0
  double taper_length_m = 2e-3;                // ∈ (0, ρ S]
  int n_along = 48;                            // segments along the arc, ≥ 2
  int n_around = 12;                           // ≥ 3
  void Validate() const;
};
TriangleMesh MakeNeedleMesh(const NeedleMeshDef& def);

// One jaw of a forceps or a needle holder. Frame J: the hinge at the origin, the jaw along +x
// from 0 to length; the flat inner (gripping) face in the plane y = 0, spanning z ∈ ±width/2;
// the back a half ellipse out to y = height. The cross-section shrinks linearly to tip_scale of
// its size at the tip. Closed (a frustum of the cross-section polygon).
struct JawMeshDef {
  double length_m = 8e-3;    // > 0
  double width_m = 0.8e-3;   // across the inner face at the hinge, > 0
  double height_m = 0.5e-3;  // from the inner face to the back at the hinge, > 0
  double tip_scale = 0.3;    // ∈ (0, 1]
  int n_back = 8;            // segments around the back, ≥ 2
  void Validate() const;
};
TriangleMesh MakeJawMesh(const JawMeshDef& def);

// The two jaws in the tool frame T: the hinge at the origin, the jaws along +x opening in the
// xy-plane, the upper jaw (side +1, its back towards +y) turned by +opening/2 about +z, the lower
// jaw (side −1) the upper one turned by π about +x and then by −opening/2 about +z. Opening 0:
// the inner faces meet in the plane y = 0.
Eigen::Isometry3d CalcJawPose(int side, double opening_angle_rad);  // X_TJ; side ±1
// Both jaws in T at the given opening (rad, in [0, π)); throws std::invalid_argument otherwise.
TriangleMesh MakeJawPairMesh(const JawMeshDef& def, double opening_angle_rad);

// A tissue patch: a slab under a grid surface. Frame S: the top surface z = 0 over
// x ∈ ±size_x/2, y ∈ ±size_y/2, the bottom z = −thickness. The first (nx + 1)(ny + 1) vertices
// are the top grid, vertex (i, j) at index i + (nx + 1) j (x = −size_x/2 + size_x i / nx), so a
// view can move them to show the deformed surface; the bottom grid follows in the same order.
struct TissueSlabMeshDef {
  double size_x_m = 20e-3;    // > 0
  double size_y_m = 20e-3;    // > 0
  double thickness_m = 2e-3;  // > 0
  int nx = 20;                // ≥ 1
  int ny = 20;                // ≥ 1
  void Validate() const;
};
TriangleMesh MakeTissueSlabMesh(const TissueSlabMeshDef& def);

// A UV sphere around the origin: n_lat bands from the pole at +z to the one at −z.
struct SphereMeshDef {
  double radius_m = 0.5e-3;  // > 0
  int n_lat = 12;            // ≥ 2
  int n_lon = 24;            // ≥ 3
  void Validate() const;
};
TriangleMesh MakeSphereMesh(const SphereMeshDef& def);

// A closed cylinder, its axis along z, centred at the origin (z ∈ ±length/2).
struct CylinderMeshDef {
  double radius_m = 0.5e-3;  // > 0
  double length_m = 1e-3;    // > 0
  int n_around = 24;         // ≥ 3
  void Validate() const;
};
TriangleMesh MakeCylinderMesh(const CylinderMeshDef& def);

// A box centred at the origin, its edges along the axes: 8 vertices, 12 triangles.
struct BoxMeshDef {
  Eigen::Vector3d size_m = Eigen::Vector3d::Constant(1e-3);  // each > 0
  void Validate() const;
};
TriangleMesh MakeBoxMesh(const BoxMeshDef& def);

}  // namespace microdex::mesh
