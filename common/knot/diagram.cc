#include "common/knot/diagram.h"

#include <numeric>

#include "common/base/check.h"

namespace microdex::knot {
namespace {

// Keeps the passages whose crossing is not marked `removed`, renumbering crossings densely.
GaussCode RemoveCrossings(const GaussCode& code, const std::vector<bool>& removed) {
  std::vector<int> new_id(code.sign.size(), -1);
  GaussCode out;
  for (int c = 0; c < code.num_crossings(); ++c) {
    if (!removed[c]) {
      new_id[c] = static_cast<int>(out.sign.size());
      out.sign.push_back(code.sign[c]);
    }
  }
  for (const Passage& p : code.passages) {
    if (!removed[p.crossing]) out.passages.push_back({new_id[p.crossing], p.over});
  }
  return out;
}

// One pass of Reidemeister I: a crossing passed twice in a row (cyclically) is a kink.
bool RemoveKinks(GaussCode& code) {
  const int m = static_cast<int>(code.passages.size());
  if (m == 0) return false;
  std::vector<bool> removed(code.sign.size(), false);
  bool any = false;
  for (int k = 0; k < m; ++k) {
    const Passage& a = code.passages[k];
    const Passage& b = code.passages[(k + 1) % m];
    if (a.crossing == b.crossing && !removed[a.crossing]) {
      removed[a.crossing] = true;
      any = true;
      // Removing one kink can create another next to it; the caller loops.
      break;
    }
  }
  if (any) code = RemoveCrossings(code, removed);
  return any;
}

// One Reidemeister II move on a bigon face, if any.
bool RemoveBigon(GaussCode& code) {
  if (code.num_crossings() < 2) return false;
  const PlanarDiagram pd = MakePlanarDiagram(code);
  const int n = pd.num_crossings();
  // The first corner met of each face.
  std::vector<int> first_corner(pd.num_faces, -1);
  for (int corner = 0; corner < 4 * n; ++corner) {
    int& f = first_corner[pd.face_of_corner[corner]];
    if (f < 0) f = corner;
  }
  for (int face = 0; face < pd.num_faces; ++face) {
    if (pd.face_size[face] != 2) continue;
    const int c1 = first_corner[face] / 4;
    const int p1 = first_corner[face] % 4;
    const int e1 = pd.slots[c1][(p1 + 1) % 4];
    const CrossingSlot at_c1{c1, (p1 + 1) % 4};
    const CrossingSlot far =
        pd.edge_ends[e1][0] == at_c1 ? pd.edge_ends[e1][1] : pd.edge_ends[e1][0];
    const int c2 = far.crossing;
    if (c2 == c1) continue;
    const int e2 = pd.slots[c2][(far.slot + 1) % 4];
    const bool e1_over = pd.edge_starts_over(e1) && pd.edge_ends_over(e1);
    const bool e1_under = !pd.edge_starts_over(e1) && !pd.edge_ends_over(e1);
    const bool e2_over = pd.edge_starts_over(e2) && pd.edge_ends_over(e2);
    const bool e2_under = !pd.edge_starts_over(e2) && !pd.edge_ends_over(e2);
    if ((e1_over && e2_under) || (e1_under && e2_over)) {
      std::vector<bool> removed(code.sign.size(), false);
      removed[c1] = removed[c2] = true;
      code = RemoveCrossings(code, removed);
      return true;
    }
  }
  return false;
}

}  // namespace

PlanarDiagram MakePlanarDiagram(const GaussCode& code) {
  PlanarDiagram pd;
  pd.code = code;
  const int n = code.num_crossings();
  const int m = static_cast<int>(code.passages.size());
  MICRODEX_CHECK(m == 2 * n);
  pd.slots.assign(n, {-1, -1, -1, -1});
  pd.edge_ends.resize(m);
  for (int k = 0; k < m; ++k) {
    const Passage& p = code.passages[k];
    const int in_edge = (k + m - 1) % m;
    const int out_edge = k;
    int in_slot = 0;
    int out_slot = 2;
    if (p.over) {
      const bool positive = code.sign[p.crossing] > 0;
      in_slot = positive ? 3 : 1;
      out_slot = positive ? 1 : 3;
    }
    auto& s = pd.slots[p.crossing];
    MICRODEX_CHECK(s[in_slot] < 0 && s[out_slot] < 0);
    s[in_slot] = in_edge;
    s[out_slot] = out_edge;
    pd.edge_ends[in_edge][1] = {p.crossing, in_slot};
    pd.edge_ends[out_edge][0] = {p.crossing, out_slot};
  }
  // Faces: from corner (c, p) follow the edge in slot p + 1 to its other end (c', q); the
  // same face continues at corner (c', q).
  pd.face_of_corner.assign(4 * n, -1);
  for (int start = 0; start < 4 * n; ++start) {
    if (pd.face_of_corner[start] >= 0) continue;
    const int face = pd.num_faces++;
    int size = 0;
    int corner = start;
    while (pd.face_of_corner[corner] < 0) {
      pd.face_of_corner[corner] = face;
      ++size;
      const CrossingSlot here{corner / 4, (corner % 4 + 1) % 4};
      const int e = pd.slots[here.crossing][here.slot];
      const CrossingSlot there =
          pd.edge_ends[e][0] == here ? pd.edge_ends[e][1] : pd.edge_ends[e][0];
      corner = 4 * there.crossing + there.slot;
    }
    MICRODEX_CHECK(corner == start);
    pd.face_size.push_back(size);
  }
  // Euler on the sphere: V - E + F = n - 2n + F = 2.
  MICRODEX_CHECK(n == 0 || pd.num_faces == n + 2);
  return pd;
}

GaussCode SimplifyReidemeister(const GaussCode& code) {
  GaussCode out = code;
  for (;;) {
    while (RemoveKinks(out)) {
    }
    if (!RemoveBigon(out)) break;
  }
  return out;
}

int Writhe(const GaussCode& code) { return std::accumulate(code.sign.begin(), code.sign.end(), 0); }

}  // namespace microdex::knot
