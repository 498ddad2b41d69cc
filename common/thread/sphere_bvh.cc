#include "common/thread/sphere_bvh.h"

#include <algorithm>
#include <utility>

#include "common/base/check.h"

namespace microdex::thread {
namespace {

int BuildRange(SphereBvhTopology& t, int lo, int hi) {
  if (hi - lo == 1) {
    t.left.push_back(-1);
    t.right.push_back(-1);
    t.leaf_link.push_back(lo);
    t.height.push_back(0);
    return static_cast<int>(t.left.size()) - 1;
  }
  const int mid = (lo + hi) / 2;
  const int l = BuildRange(t, lo, mid);
  const int r = BuildRange(t, mid, hi);
  t.left.push_back(l);
  t.right.push_back(r);
  t.leaf_link.push_back(-1);
  t.height.push_back(std::max(t.height[l], t.height[r]) + 1);
  return static_cast<int>(t.left.size()) - 1;
}

bool Overlap(const SphereBvhSpheres& s, int i, int j) {
  const double r = s.radius_m[i] + s.radius_m[j];
  return (s.center_W.col(i) - s.center_W.col(j)).squaredNorm() <= r * r;
}

struct Collector {
  const SphereBvhTopology& t;
  const SphereBvhSpheres& s;
  LinkPair* pairs;
  int capacity;
  int count = 0;

  void Save(int link_a, int link_b) {
    if (link_a > link_b) std::swap(link_a, link_b);
    if (link_b - link_a <= 1) return;  // the same link or neighbours sharing a node
    if (count < capacity) pairs[count] = {link_a, link_b};
    ++count;
  }

  // FindCollision (thesis §5.3).
  void FindCollision(int t1, int t2) {
    if (!Overlap(s, t1, t2)) return;
    if (t.leaf_link[t1] >= 0 && t.leaf_link[t2] >= 0) {
      Save(t.leaf_link[t1], t.leaf_link[t2]);
      return;
    }
    if (t.height[t1] > t.height[t2]) std::swap(t1, t2);
    FindCollision(t1, t.left[t2]);
    FindCollision(t1, t.right[t2]);
  }

  void Self(int node) {
    if (t.leaf_link[node] >= 0) return;
    Self(t.left[node]);
    Self(t.right[node]);
    FindCollision(t.left[node], t.right[node]);
  }
};

}  // namespace

SphereBvhTopology BuildSphereBvhTopology(int num_links) {
  MICRODEX_CHECK(num_links >= 1);
  SphereBvhTopology t;
  t.num_leaves = num_links;
  t.left.reserve(2 * num_links - 1);
  t.right.reserve(2 * num_links - 1);
  t.leaf_link.reserve(2 * num_links - 1);
  t.height.reserve(2 * num_links - 1);
  t.root = BuildRange(t, 0, num_links);
  t.leaf_node.assign(num_links, -1);
  for (int i = 0; i < static_cast<int>(t.leaf_link.size()); ++i) {
    if (t.leaf_link[i] >= 0) t.leaf_node[t.leaf_link[i]] = i;
  }
  MICRODEX_CHECK(static_cast<int>(t.left.size()) == 2 * num_links - 1);
  return t;
}

SphereBvhSpheres MakeSphereBvhSpheres(const SphereBvhTopology& topology) {
  const int n = static_cast<int>(topology.left.size());
  SphereBvhSpheres s;
  s.center_W = Eigen::Matrix3Xd::Zero(3, n);
  s.radius_m = Eigen::VectorXd::Zero(n);
  return s;
}

int RefitSphereBvh(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                   SphereBvhSpheres& s) {
  const int n = static_cast<int>(t.left.size());
  for (int i = 0; i < n; ++i) {  // post-order: children are refitted before their parent
    const int link = t.leaf_link[i];
    if (link >= 0) {
      s.center_W.col(i) = 0.5 * (x_W.col(link) + x_W.col(link + 1));
      s.radius_m[i] = 0.5 * (x_W.col(link + 1) - x_W.col(link)).norm() + inflate_m;
      continue;
    }
    const int a = t.left[i];
    const int b = t.right[i];
    const Eigen::Vector3d d = s.center_W.col(b) - s.center_W.col(a);
    const double dist = d.norm();
    const double ra = s.radius_m[a];
    const double rb = s.radius_m[b];
    if (dist + rb <= ra) {
      s.center_W.col(i) = s.center_W.col(a);
      s.radius_m[i] = ra;
    } else if (dist + ra <= rb) {
      s.center_W.col(i) = s.center_W.col(b);
      s.radius_m[i] = rb;
    } else {
      const double r = 0.5 * (dist + ra + rb);
      s.center_W.col(i) = s.center_W.col(a) + ((r - ra) / dist) * d;
      s.radius_m[i] = r;
    }
  }
  return n;
}

int FindSelfCollisions(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                       LinkPair* pairs, int capacity) {
  Collector c{topology, spheres, pairs, capacity};
  c.Self(topology.root);
  return c.count;
}

int FindSelfCollisionsAllPairs(const SphereBvhTopology& topology, const SphereBvhSpheres& spheres,
                               LinkPair* pairs, int capacity) {
  const int n = topology.num_leaves;
  int count = 0;
  for (int la = 0; la < n; ++la) {
    for (int lb = la + 2; lb < n; ++lb) {
      if (!Overlap(spheres, topology.leaf_node[la], topology.leaf_node[lb])) continue;
      if (count < capacity) pairs[count] = {la, lb};
      ++count;
    }
  }
  return count;
}

}  // namespace microdex::thread
