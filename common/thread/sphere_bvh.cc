#include "common/thread/sphere_bvh.h"

#include <algorithm>
#include <cmath>

#include "common/base/check.h"

namespace microdex::thread {
namespace {

// Fixed traversal stack: FindCollision pushes two pairs per split and a pair's depth is at most
// height(left) + height(right), so 2 * (2 * 32) covers any tree of up to 2^32 leaves.
constexpr int kStackCapacity = 128;
constexpr double kRelativeSlack = 1e-12;

struct PendingPair {
  int p;
  int q;
};

inline bool Overlap(const double* s, int i, int j) {
  const double* a = s + 4 * i;
  const double* b = s + 4 * j;
  const double dx = a[0] - b[0];
  const double dy = a[1] - b[1];
  const double dz = a[2] - b[2];
  const double r = a[3] + b[3];
  return dx * dx + dy * dy + dz * dz <= r * r;
}

inline void FitLeaf(const double* x, int link, double inflate_m, double* out) {
  const double* a = x + 3 * link;
  const double* b = a + 3;
  const double dx = b[0] - a[0];
  const double dy = b[1] - a[1];
  const double dz = b[2] - a[2];
  out[0] = 0.5 * (a[0] + b[0]);
  out[1] = 0.5 * (a[1] + b[1]);
  out[2] = 0.5 * (a[2] + b[2]);
  out[3] = 0.5 * std::sqrt(dx * dx + dy * dy + dz * dz) + inflate_m;
}

}  // namespace

SphereBvhTopology BuildSphereBvhTopology(int num_links) {
  MICRODEX_CHECK(num_links >= 1);
  SphereBvhTopology t;
  t.num_leaves = num_links;
  t.nodes.reserve(2 * num_links - 1);
  t.height.reserve(2 * num_links - 1);
  std::vector<int> level;
  for (int l = 0; l < num_links; ++l) {
    t.nodes.push_back({-1, -1, l, l + 1});
    t.height.push_back(0);
    level.push_back(l);
  }
  // Pair successive spheres level by level (thesis §5.3); an odd last one moves up unchanged.
  while (level.size() > 1) {
    std::vector<int> up;
    for (size_t k = 0; k + 1 < level.size(); k += 2) {
      const int a = level[k];
      const int b = level[k + 1];
      t.nodes.push_back({a, b, t.nodes[a].lo, t.nodes[b].hi});
      t.height.push_back(std::max(t.height[a], t.height[b]) + 1);
      up.push_back(static_cast<int>(t.nodes.size()) - 1);
    }
    if (level.size() % 2 == 1) up.push_back(level.back());
    level.swap(up);
  }
  t.root = level[0];
  MICRODEX_CHECK(static_cast<int>(t.nodes.size()) == 2 * num_links - 1);
  t.max_stack = 2 * (2 * t.height[t.root] + 1);
  MICRODEX_CHECK(t.max_stack <= kStackCapacity);
  return t;
}

SphereBvhSpheres MakeSphereBvhSpheres(const SphereBvhTopology& topology) {
  SphereBvhSpheres s;
  s.xyzr = Eigen::Matrix4Xd::Zero(4, static_cast<Eigen::Index>(topology.nodes.size()));
  return s;
}

int RefitSphereBvhLeaves(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                         SphereBvhSpheres& s) {
  const double* x = x_W.data();
  double* out = s.xyzr.data();
  for (int l = 0; l < t.num_leaves; ++l) FitLeaf(x, l, inflate_m, out + 4 * l);
  return t.num_leaves;
}

int RefitSphereBvh(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                   SphereBvhSpheres& s) {
  RefitSphereBvhLeaves(t, x_W, inflate_m, s);
  double* out = s.xyzr.data();
  const int n = static_cast<int>(t.nodes.size());
  for (int i = t.num_leaves; i < n; ++i) {  // children precede their parent
    const SphereBvhNode& node = t.nodes[i];
    const double* a = out + 4 * node.left;
    const double* b = out + 4 * node.right;
    double* c = out + 4 * i;
    const double dx = b[0] - a[0];
    const double dy = b[1] - a[1];
    const double dz = b[2] - a[2];
    const double dist = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double ra = a[3];
    const double rb = b[3];
    if (dist + rb <= ra) {
      std::copy(a, a + 4, c);
    } else if (dist + ra <= rb) {
      std::copy(b, b + 4, c);
    } else {
      const double r = 0.5 * (dist + ra + rb);
      const double w = (r - ra) / dist;
      c[0] = a[0] + w * dx;
      c[1] = a[1] + w * dy;
      c[2] = a[2] + w * dz;
      // Rounding of the centre must not let a child stick out: a pair of leaves that just
      // touch has to be reached through their ancestors.
      c[3] = r * (1.0 + kRelativeSlack);
    }
  }
  return n;
}

int FindSelfCollisions(const SphereBvhTopology& t, const SphereBvhSpheres& spheres, LinkPair* pairs,
                       int capacity) {
  const double* s = spheres.xyzr.data();
  const SphereBvhNode* nodes = t.nodes.data();
  PendingPair stack[kStackCapacity];
  int count = 0;
  const int n = static_cast<int>(t.nodes.size());
  // Self(T) for every inner node T: FindCollision(left, right). Links under `p` always precede
  // the links under `q`, so a pair of leaves is (p's link, q's link) in increasing order.
  for (int i = t.num_leaves; i < n; ++i) {
    int top = 0;
    stack[top++] = {nodes[i].left, nodes[i].right};
    while (top > 0) {
      const PendingPair pq = stack[--top];
      const SphereBvhNode& p = nodes[pq.p];
      const SphereBvhNode& q = nodes[pq.q];
      // All links of q within one of all links of p: only the same or neighbouring links.
      if (q.hi - 1 - p.lo <= 1) continue;
      if (!Overlap(s, pq.p, pq.q)) continue;
      const bool p_leaf = p.left < 0;
      const bool q_leaf = q.left < 0;
      if (p_leaf && q_leaf) {
        if (count < capacity) pairs[count] = {p.lo, q.lo};
        ++count;
        continue;
      }
      // Descend into the larger of the two (FindCollision's "level higher" rule).
      if (q_leaf || (!p_leaf && p.hi - p.lo > q.hi - q.lo)) {
        stack[top++] = {p.right, pq.q};
        stack[top++] = {p.left, pq.q};
      } else {
        stack[top++] = {pq.p, q.right};
        stack[top++] = {pq.p, q.left};
      }
    }
  }
  return count;
}

int FindSelfCollisionsAllPairs(const SphereBvhTopology& t, const SphereBvhSpheres& spheres,
                               LinkPair* pairs, int capacity) {
  const int n = t.num_leaves;
  const double* s = spheres.xyzr.data();
  int count = 0;
  for (int la = 0; la < n; ++la) {
    for (int lb = la + 2; lb < n; ++lb) {
      if (!Overlap(s, la, lb)) continue;
      if (count < capacity) pairs[count] = {la, lb};
      ++count;
    }
  }
  return count;
}

}  // namespace microdex::thread
