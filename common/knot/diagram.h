#pragma once
// Knot diagrams: the signed Gauss code of a projection, its planar-diagram (PD) form with the
// faces of the projection on the sphere, and Reidemeister I/II simplification.

#include <array>
#include <vector>

namespace microdex::knot {

// One passage of the closed curve through a crossing of its projection.
struct Passage {
  int crossing = 0;
  bool over = false;
};

// Signed Gauss code: the passages in the order of the curve's orientation, each crossing
// passed twice (once over, once under); sign[c] is +1 for a positive (right-handed) crossing,
// -1 for a negative one.
struct GaussCode {
  std::vector<Passage> passages;
  std::vector<int> sign;
  int num_crossings() const { return static_cast<int>(sign.size()); }
};

// (crossing, slot) of an edge end in a PlanarDiagram.
struct CrossingSlot {
  int crossing = 0;
  int slot = 0;
  bool operator==(const CrossingSlot&) const = default;
};

// PD code of a Gauss code. Edge k runs from passage k to passage k+1 (cyclically). slots[c]
// lists the four edge ends at crossing c counter-clockwise as seen by the viewer, starting
// with the incoming under-edge: slot 0 under in, slot 2 under out, slots 1 and 3 the
// over-strand (it runs 3 -> 1 at a positive crossing, 1 -> 3 at a negative one).
struct PlanarDiagram {
  GaussCode code;
  std::vector<std::array<int, 4>> slots;
  // edge_ends[k] = {start (at passage k), end (at passage k + 1)}.
  std::vector<std::array<CrossingSlot, 2>> edge_ends;
  // Faces of the projection on the sphere. Corner (c, p) is the face sector between slot p
  // and slot p + 1 (counter-clockwise); face_of_corner[4 c + p] is its face.
  std::vector<int> face_of_corner;
  std::vector<int> face_size;  // corners per face
  int num_faces = 0;

  int num_crossings() const { return code.num_crossings(); }
  int num_edges() const { return static_cast<int>(code.passages.size()); }
  bool edge_starts_over(int e) const { return code.passages[e].over; }
  bool edge_ends_over(int e) const { return code.passages[(e + 1) % num_edges()].over; }
};

// Builds the PD code and the faces. A planar Gauss code (one from a projection) has
// n + 2 faces; this is checked.
PlanarDiagram MakePlanarDiagram(const GaussCode& code);

// Removes the crossings of every Reidemeister I loop (monogon face) and II bigon (a face
// with two corners whose one edge is over at both ends and the other under at both ends),
// until none is left. Crossing ids are renumbered densely.
GaussCode SimplifyReidemeister(const GaussCode& code);

// Sum of the crossing signs.
int Writhe(const GaussCode& code);

}  // namespace microdex::knot
