#pragma once
// The object's geometry as the contact generation sees it: mass properties, the surface points
// that can touch a plane, and the interval where a line crosses the body. Everything is in the
// body frame O (origin at the centre of mass, principal axes) and allocation-free.
//
// Plugging in another shape (README.md "Shapes"): a triangle mesh becomes a fourth kind whose
// support points are the vertices of its convex hull (or of the mesh, for a non-convex one)
// that lie within the plane's margin, precomputed once at model build into a fixed array, and
// whose line interval comes from a ray cast against the mesh (a BVH built at model build). The
// contact generation (grasp_contacts.cc) only calls the two functions below.

#include <Eigen/Core>
#include <array>

#include "common/grasp/grasp_def.h"

namespace microdex::grasp {

// At most this many support points per shape and plane.
inline constexpr int kMaxSupportPoints = 8;

struct ShapeGeometry {
  ShapeKind kind = ShapeKind::kBox;
  Eigen::Vector3d half_extents_m = Eigen::Vector3d::Zero();  // box
  double radius_m = 0.0;                                     // cylinder, sphere
  double half_length_m = 0.0;                                // cylinder
  double bounding_radius_m = 0.0;  // of the sphere about O that holds the shape
};

struct MassProperties {
  double mass_kg = 0.0;
  Eigen::Vector3d inertia_kg_m2 = Eigen::Vector3d::Zero();  // principal moments about O
};

ShapeGeometry MakeShapeGeometry(const ShapeDef& def);
// Solid of uniform density: analytic mass and principal moments.
MassProperties CalcMassProperties(const ShapeDef& def, double density_kg_per_m3);

// The points of the surface that can touch a plane whose outward normal (from the plane into
// the object's side) is -d_O, i.e. the candidates furthest along d_O: a box's 8 vertices, a
// sphere's one support point, a cylinder's rim points in d_O's direction and at ±90° and 180°
// from it on both caps (8). Returns how many were written; point k keeps its index as the
// object's direction changes slowly (warm start keys).
int CalcSupportPoints(const ShapeGeometry& shape, const Eigen::Vector3d& d_O,
                      std::array<Eigen::Vector3d, kMaxSupportPoints>& points_O);

// At most this many support edges per shape.
inline constexpr int kMaxSupportEdges = 12;
using SupportEdges = std::array<std::array<int, 2>, kMaxSupportEdges>;

// The straight edges between support points (indices into CalcSupportPoints' output), which a
// bounded face clips: a box's 12 edges, a cylinder's 4 side lines through its rim points; none
// for a sphere. Returns how many were written.
int CalcSupportEdges(const ShapeGeometry& shape, SupportEdges& edges);

// Where the line p_O + s d_O (d_O unit) is inside the body: [s_in, s_out]. Returns false when
// the line misses it.
bool CalcLineInterval(const ShapeGeometry& shape, const Eigen::Vector3d& p_O,
                      const Eigen::Vector3d& d_O, double& s_in, double& s_out);

}  // namespace microdex::grasp
