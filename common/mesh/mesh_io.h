#pragma once
// Mesh files through assimp: Wavefront OBJ, Stanford PLY (ASCII or binary), glTF 2.0 (.gltf with
// its .bin, or binary .glb).
//
// Units and axes: a file's coordinates are metres, in the frame its generator documents
// (primitives.h); they are read and written as they are — no unit scaling and no axis change
// (glTF's "Y up" convention is not applied). Assimp stores coordinates as 32-bit floats, so a
// round trip moves a vertex by up to ~6e-8 of its distance from the origin (3e-10 m at 5 mm).

#include <string>

#include "common/mesh/triangle_mesh.h"

namespace microdex::mesh {

// Every triangle of every mesh of the file, in the file's root frame: the node transforms are
// applied (normals by the inverse transpose), polygons triangulated, points and lines dropped.
// Vertices of one mesh that assimp duplicated per face corner (OBJ, PLY) are joined again where
// their position and normal are bit-for-bit equal — never by a distance threshold, which would
// close gaps of a micrometre-scale mesh. Normals are returned when every mesh of the file has
// them. Throws microdex::InputError ("FILE: reason"): "cannot open file"; assimp's reason for an
// unreadable or corrupt file; "no triangles"; a non-finite coordinate, naming the mesh and the
// vertex in the field.
TriangleMesh LoadMesh(const std::string& path);

// Writes the mesh (and its normals, when there is one per vertex) in the format of the path's
// extension: .obj (no material file), .ply (binary little-endian), .glb (binary glTF 2.0), .gltf
// (glTF 2.0 JSON with a .bin beside it). An OBJ file always carries normals (assimp's exporter
// insists): CalcVertexNormals' when the mesh has none. A glTF file stores the vertices in units
// of 1/1024 m under a root node that scales them to metres (assimp's glTF exporter joins
// vertices closer than 1e-5 file units, which at metres would merge a needle tip's); glTF
// readers, LoadMesh among them, apply the node and see metres. Throws std::invalid_argument for an
// extension of none of these, a mesh with no triangles, an index out of range or a non-finite
// coordinate, and std::runtime_error ("FILE: reason") when assimp cannot write the file.
void SaveMesh(const TriangleMesh& mesh, const std::string& path);

}  // namespace microdex::mesh
