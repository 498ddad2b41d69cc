#include "common/thread/sphere_bvh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "common/base/check.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace microdex::thread {
namespace {

// Fall-back stack: FindCollision pushes two pairs per split and a pair's depth is at most
// height(p) + height(q), so 2 * (2 * 32) covers any tree of up to 2^32 leaves.
constexpr int kStackCapacity = 128;
// Smallest traversal queue; it holds at least four pending pairs per tree node.
constexpr size_t kMinQueue = 256;
// Pairs of nodes of at most this many links are tested as their (up to four) leaf pairs.
constexpr int kSmall = 2;

// Rounding margins of the single-precision spheres (float epsilon is 2^-23, unit roundoff
// 2^-24). A radius is grown by 2^-18 of itself (32 epsilon: the few roundings of the radius,
// of the centre's offset w (b - a) <= 2 r, and of the overlap test itself) plus 2^-21 of the
// L1 norms of the two points or centres it is built from (the centre's rounding, at most
// 2^-24 of their size per operation and coordinate). Checked by the containment test in
// double precision.
constexpr float kGrow = 1.0f + 0x1p-18f;
constexpr float kSlack = 0x1p-21f;

// Four floats: SSE2 where available, a plain loop otherwise. Both perform the same IEEE
// operations in the same order, so the scalar paths give the same spheres and tests.
#if defined(__SSE2__)
struct F4 {
  __m128 v;
};
inline F4 Splat(float a) { return {_mm_set1_ps(a)}; }
inline F4 Load(const float* p) { return {_mm_load_ps(p)}; }  // 16-byte aligned
inline F4 LoadU(const float* p) { return {_mm_loadu_ps(p)}; }
inline void Store(float* p, F4 a) { _mm_store_ps(p, a.v); }
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4 operator/(F4 a, F4 b) { return {_mm_div_ps(a.v, b.v)}; }
inline F4 Sqrt(F4 a) { return {_mm_sqrt_ps(a.v)}; }
inline F4 Max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
inline F4 Min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
inline F4 Abs(F4 a) { return {_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v)}; }
inline void Transpose(F4& a, F4& b, F4& c, F4& d) { _MM_TRANSPOSE4_PS(a.v, b.v, c.v, d.v); }
// (u0, u2, w0, w2) and (u1, u3, w1, w3).
inline void Deinterleave(F4 u, F4 w, F4& even, F4& odd) {
  even.v = _mm_shuffle_ps(u.v, w.v, _MM_SHUFFLE(2, 0, 2, 0));
  odd.v = _mm_shuffle_ps(u.v, w.v, _MM_SHUFFLE(3, 1, 3, 1));
}
// Spheres a = (x, y, z, r) and b overlap: ((dx² + dz²) + (dy² - (ra + rb)²)) <= 0. With rb
// negated, a - b holds (dx, dy, dz, ra + rb); negating the last square gives the four terms.
inline bool Overlap(const float* a, const float* b) {
  const __m128 sign_w = _mm_castsi128_ps(_mm_set_epi32(INT32_MIN, 0, 0, 0));
  const __m128 d = _mm_sub_ps(_mm_load_ps(a), _mm_xor_ps(_mm_load_ps(b), sign_w));
  const __m128 v = _mm_xor_ps(_mm_mul_ps(d, d), sign_w);
  const __m128 h = _mm_add_ps(v, _mm_movehl_ps(v, v));
  const __m128 sum = _mm_add_ss(h, _mm_shuffle_ps(h, h, _MM_SHUFFLE(1, 1, 1, 1)));
  return _mm_cvtss_f32(sum) <= 0.0f;
}
#else
struct F4 {
  float v[4];
};
template <class Op>
inline F4 Lanes(F4 a, F4 b, Op op) {
  F4 c;
  for (int k = 0; k < 4; ++k) c.v[k] = op(a.v[k], b.v[k]);
  return c;
}
inline F4 Splat(float a) { return {{a, a, a, a}}; }
inline F4 Load(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
inline F4 LoadU(const float* p) { return Load(p); }
inline void Store(float* p, F4 a) { std::copy(a.v, a.v + 4, p); }
inline F4 operator+(F4 a, F4 b) {
  return Lanes(a, b, [](float x, float y) { return x + y; });
}
inline F4 operator-(F4 a, F4 b) {
  return Lanes(a, b, [](float x, float y) { return x - y; });
}
inline F4 operator*(F4 a, F4 b) {
  return Lanes(a, b, [](float x, float y) { return x * y; });
}
inline F4 operator/(F4 a, F4 b) {
  return Lanes(a, b, [](float x, float y) { return x / y; });
}
inline F4 Sqrt(F4 a) {
  return Lanes(a, a, [](float x, float) { return std::sqrt(x); });
}
// As maxps / minps: the second operand unless the comparison holds.
inline F4 Max(F4 a, F4 b) {
  return Lanes(a, b, [](float x, float y) { return x > y ? x : y; });
}
inline F4 Min(F4 a, F4 b) {
  return Lanes(a, b, [](float x, float y) { return x < y ? x : y; });
}
inline F4 Abs(F4 a) {
  return Lanes(a, a, [](float x, float) { return std::fabs(x); });
}
inline void Transpose(F4& a, F4& b, F4& c, F4& d) {
  F4* rows[4] = {&a, &b, &c, &d};
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) std::swap(rows[i]->v[j], rows[j]->v[i]);
  }
}
inline void Deinterleave(F4 u, F4 w, F4& even, F4& odd) {
  even = {{u.v[0], u.v[2], w.v[0], w.v[2]}};
  odd = {{u.v[1], u.v[3], w.v[1], w.v[3]}};
}
#endif

// The scalar twins of the lane operations (same semantics as the SSE instructions).
inline float Splat1(float a) { return a; }
inline float Sqrt(float a) { return std::sqrt(a); }
inline float Max(float a, float b) { return a > b ? a : b; }
inline float Min(float a, float b) { return a < b ? a : b; }
inline float Abs(float a) { return std::fabs(a); }

template <class T>
T Constant(float a) {
  if constexpr (std::is_same_v<T, float>) {
    return Splat1(a);
  } else {
    return Splat(a);
  }
}

// Minimal sphere of the link a-b grown by inflate, plus the rounding margin.
template <class T>
inline void FitLeaf(T ax, T ay, T az, T bx, T by, T bz, T inflate, T& cx, T& cy, T& cz, T& cr) {
  const T half = Constant<T>(0.5f);
  const T dx = bx - ax;
  const T dy = by - ay;
  const T dz = bz - az;
  const T len = Sqrt(dx * dx + dy * dy + dz * dz);
  cx = half * (ax + bx);
  cy = half * (ay + by);
  cz = half * (az + bz);
  cr = (half * len + inflate) * Constant<T>(kGrow) +
       Constant<T>(kSlack) * (Abs(ax) + Abs(ay) + Abs(az) + Abs(bx) + Abs(by) + Abs(bz));
}

// Minimal sphere enclosing the spheres a and b, plus the rounding margin. Branch free: the radius
// max(ra, rb, (|b - a| + ra + rb) / 2) and the centre a + w (b - a) with w clamped to [0, 1] also
// cover one sphere inside the other (w = 0 or 1) and coincident centres.
template <class T>
inline void FitParent(T ax, T ay, T az, T ar, T bx, T by, T bz, T br, T& cx, T& cy, T& cz, T& cr) {
  const T dx = bx - ax;
  const T dy = by - ay;
  const T dz = bz - az;
  const T dist = Sqrt(dx * dx + dy * dy + dz * dz);
  const T r = Max(Constant<T>(0.5f) * (dist + ar + br), Max(ar, br));
  const T w = Min(
      Max((r - ar) / Max(dist, Constant<T>(std::numeric_limits<float>::min())), Constant<T>(0.0f)),
      Constant<T>(1.0f));
  cx = ax + w * dx;
  cy = ay + w * dy;
  cz = az + w * dz;
  cr = r * Constant<T>(kGrow) +
       Constant<T>(kSlack) * (Abs(ax) + Abs(ay) + Abs(az) + Abs(bx) + Abs(by) + Abs(bz));
}

// The same test lane by lane: the same operations in the same order, so the same outcome.
inline bool OverlapScalar(const float* a, const float* b) {
  const float dx = a[0] - b[0];
  const float dy = a[1] - b[1];
  const float dz = a[2] - b[2];
  const float rs = a[3] + b[3];
  return (dx * dx + dz * dz) + (dy * dy - rs * rs) <= 0.0f;
}
#if !defined(__SSE2__)
inline bool Overlap(const float* a, const float* b) { return OverlapScalar(a, b); }
#endif

// The sphere test of both the traversal and the all-pairs reference.
inline bool Overlap(const float* s, int i, int j) { return Overlap(s + 4 * i, s + 4 * j); }

// FindCollision's "level higher" rule: split the pair's larger node, the second on a tie.
inline bool DescendFirst(int size_p, int size_q) { return size_p > size_q; }

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
    SphereBvhLevel lv;
    lv.begin = static_cast<int>(t.nodes.size());
    lv.first_child = level[0];
    for (size_t k = 0; k + 1 < level.size(); k += 2) {
      const int a = level[k];
      const int b = level[k + 1];
      if (a == lv.first_child + static_cast<int>(k) && b == a + 1 && lv.regular == lv.count) {
        ++lv.regular;
      }
      ++lv.count;
      t.nodes.push_back({a, b, t.nodes[a].lo, t.nodes[b].hi});
      t.height.push_back(std::max(t.height[a], t.height[b]) + 1);
      up.push_back(static_cast<int>(t.nodes.size()) - 1);
    }
    t.levels.push_back(lv);
    if (level.size() % 2 == 1) up.push_back(level.back());
    level.swap(up);
  }
  t.root = level[0];
  MICRODEX_CHECK(static_cast<int>(t.nodes.size()) == 2 * num_links - 1);
  for (const SphereBvhNode& node : t.nodes) {
    auto offset = [&](int child) {
      const SphereBvhNode& c = t.nodes[child];
      return 16u * static_cast<std::uint32_t>(child) | (c.hi - c.lo <= kSmall ? 1u : 0u);
    };
    const bool leaf = node.left < 0;
    t.traversal.push_back({leaf ? 0u : offset(node.left), leaf ? 0u : offset(node.right),
                           node.hi - node.lo, node.lo});
  }
  t.max_stack = 2 * (2 * t.height[t.root] + 1);
  MICRODEX_CHECK(t.max_stack <= kStackCapacity);
  // Self(T) contributes FindCollision(left, right) for every inner node T. Two chain-adjacent
  // nodes (the first one's last link is followed by the second one's first link) both contain
  // the chain node their links share, so their spheres always overlap: FindCollision's descent
  // along that boundary does not depend on the positions and is unrolled here, down to the
  // adjacent leaves (excluded neighbours). What remains to test are the pairs it branches
  // into, which are never adjacent, so every pair of links below them is a candidate. At the
  // bottom of each boundary these are a node of two leaves against the next leaf but one,
  // which nearly always overlap (on a straight thread too): that test is skipped and its two
  // leaf pairs are tested directly (the same pairs are found; a test is saved).
  auto add_start = [&](int p, int q) {
    const SphereBvhNode& np = t.nodes[p];
    const SphereBvhNode& nq = t.nodes[q];
    if ((np.hi - np.lo) * (nq.hi - nq.lo) > 2) {
      t.self_pairs.push_back(PackNodePair(p, q));
      return;
    }
    for (int a = np.lo; a < np.hi; ++a) {
      for (int b = nq.lo; b < nq.hi; ++b) t.self_leaf_pairs.push_back(PackNodePair(a, b));
    }
  };
  for (int i = num_links; i < static_cast<int>(t.nodes.size()); ++i) {
    int p = t.nodes[i].left;
    int q = t.nodes[i].right;
    while (!(t.IsLeaf(p) && t.IsLeaf(q))) {
      const SphereBvhNode& np = t.nodes[p];
      const SphereBvhNode& nq = t.nodes[q];
      if (DescendFirst(t.traversal[p].size, t.traversal[q].size)) {
        add_start(np.left, q);
        p = np.right;
      } else {
        add_start(p, nq.right);
        q = nq.left;
      }
    }
  }
  return t;
}

SphereBvhSpheres MakeSphereBvhSpheres(const SphereBvhTopology& topology) {
  SphereBvhSpheres s;
  s.xyzr.setZero(4, static_cast<Eigen::Index>(topology.nodes.size()));
  s.nodes_W.setZero(topology.num_leaves + 1, 3);
  size_t size = kMinQueue;
  while (size < 4 * topology.nodes.size()) size *= 2;
  s.queue.resize(size);
  s.small_queue.resize(size);
  return s;
}

namespace {

// The nodes in single precision, one array per coordinate, for the leaf fits.
struct LeafInputs {
  const float *px, *py, *pz;
  float* out;
  float inflate;
};
LeafInputs PrepareLeaves(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                         SphereBvhSpheres& s) {
  MICRODEX_CHECK(x_W.cols() == t.num_leaves + 1);
  s.nodes_W = x_W.transpose().cast<float>();
  return {s.nodes_W.col(0).data(), s.nodes_W.col(1).data(), s.nodes_W.col(2).data(), s.xyzr.data(),
          static_cast<float>(inflate_m)};
}

// The sphere of inner node i from its children's, one sphere at a time.
void FitParentScalar(const SphereBvhTopology& t, int i, float* out) {
  const float* a = out + 4 * t.nodes[i].left;
  const float* b = out + 4 * t.nodes[i].right;
  float* c = out + 4 * i;
  FitParent(a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3], c[0], c[1], c[2], c[3]);
}

}  // namespace

int RefitSphereBvhLeaves(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                         SphereBvhSpheres& s) {
  const int n = t.num_leaves;
  const auto [px, py, pz, out, inflate] = PrepareLeaves(t, x_W, inflate_m, s);
  int l = 0;
  for (; l + 4 <= n; l += 4) {  // four links at a time, then one sphere per column
    F4 x, y, z, r;
    FitLeaf(LoadU(px + l), LoadU(py + l), LoadU(pz + l), LoadU(px + l + 1), LoadU(py + l + 1),
            LoadU(pz + l + 1), Splat(inflate), x, y, z, r);
    Transpose(x, y, z, r);
    Store(out + 4 * l, x);
    Store(out + 4 * l + 4, y);
    Store(out + 4 * l + 8, z);
    Store(out + 4 * l + 12, r);
  }
  for (; l < n; ++l) {
    float* c = out + 4 * l;
    FitLeaf(px[l], py[l], pz[l], px[l + 1], py[l + 1], pz[l + 1], inflate, c[0], c[1], c[2], c[3]);
  }
  return n;
}

int RefitSphereBvh(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                   SphereBvhSpheres& s) {
  RefitSphereBvhLeaves(t, x_W, inflate_m, s);
  float* out = s.xyzr.data();
  // Level by level (a level's children are all in the levels below): four parents at a time
  // from eight successive children, the rest one by one.
  for (const SphereBvhLevel& lv : t.levels) {
    int k = 0;
    for (; k + 4 <= lv.regular; k += 4) {
      const float* c = out + 4 * (lv.first_child + 2 * k);
      F4 x01 = Load(c), y01 = Load(c + 4), z01 = Load(c + 8), r01 = Load(c + 12);
      F4 x23 = Load(c + 16), y23 = Load(c + 20), z23 = Load(c + 24), r23 = Load(c + 28);
      Transpose(x01, y01, z01, r01);  // now x01 = (a0.x, b0.x, a1.x, b1.x), ...
      Transpose(x23, y23, z23, r23);
      F4 ax, ay, az, ar, bx, by, bz, br;
      Deinterleave(x01, x23, ax, bx);
      Deinterleave(y01, y23, ay, by);
      Deinterleave(z01, z23, az, bz);
      Deinterleave(r01, r23, ar, br);
      F4 x, y, z, r;
      FitParent(ax, ay, az, ar, bx, by, bz, br, x, y, z, r);
      Transpose(x, y, z, r);
      float* p = out + 4 * (lv.begin + k);
      Store(p, x);
      Store(p + 4, y);
      Store(p + 8, z);
      Store(p + 12, r);
    }
    for (; k < lv.count; ++k) FitParentScalar(t, lv.begin + k, out);
  }
  return static_cast<int>(t.nodes.size());
}

int RefitSphereBvhScalar(const SphereBvhTopology& t, const Eigen::Matrix3Xd& x_W, double inflate_m,
                         SphereBvhSpheres& s) {
  const int n = t.num_leaves;
  const auto [px, py, pz, out, inflate] = PrepareLeaves(t, x_W, inflate_m, s);
  for (int l = 0; l < n; ++l) {
    float* c = out + 4 * l;
    FitLeaf(px[l], py[l], pz[l], px[l + 1], py[l + 1], pz[l + 1], inflate, c[0], c[1], c[2], c[3]);
  }
  for (const SphereBvhLevel& lv : t.levels) {
    for (int k = 0; k < lv.count; ++k) FitParentScalar(t, lv.begin + k, out);
  }
  return static_cast<int>(t.nodes.size());
}

bool SphereBvhSpheresOverlap(const float* a, const float* b) { return Overlap(a, b); }
bool SphereBvhSpheresOverlapScalar(const float* a, const float* b) { return OverlapScalar(a, b); }

namespace {

// FindCollision(start) depth first on the fixed stack, for a pair the queue has no room for.
// The pair is not chain-adjacent, so neither is any pair below it.
int FindCollisionOnStack(const SphereBvhTopology& t, const float* s, SphereBvhNodePair start,
                         LinkPair* pairs, int capacity, int count) {
  SphereBvhNodePair stack[kStackCapacity];
  int top = 0;
  stack[top++] = start;
  while (top > 0) {
    const SphereBvhNodePair pq = stack[--top];
    const int ip = NodePairFirst(pq);
    const int iq = NodePairSecond(pq);
    if (!Overlap(s, ip, iq)) continue;
    const SphereBvhNode& p = t.nodes[ip];
    const SphereBvhNode& q = t.nodes[iq];
    if (p.left < 0 && q.left < 0) {
      if (count < capacity) pairs[count] = {ip, iq};
      ++count;
      continue;
    }
    if (DescendFirst(t.traversal[ip].size, t.traversal[iq].size)) {
      stack[top++] = PackNodePair(p.right, iq);
      stack[top++] = PackNodePair(p.left, iq);
    } else {
      stack[top++] = PackNodePair(ip, q.right);
      stack[top++] = PackNodePair(ip, q.left);
    }
  }
  return count;
}

// FindSelfCollisions' traversal: its rings, its output and the stages that fill them.
class SelfCollisionTraversal {
 public:
  SelfCollisionTraversal(const SphereBvhTopology& t, SphereBvhSpheres& spheres, LinkPair* pairs,
                         int capacity)
      : t_(t),
        sphere_(spheres.xyzr.data()),
        sphere_bytes_(reinterpret_cast<const char*>(sphere_)),
        node_bytes_(reinterpret_cast<const char*>(t.traversal.data())),
        ring_(spheres.queue.data()),
        small_ring_(spheres.small_queue.data()),
        ring_size_(static_cast<unsigned>(spheres.queue.size())),
        small_size_(static_cast<unsigned>(spheres.small_queue.size())),
        pairs_(pairs),
        capacity_(capacity) {}

  int count() const { return count_; }

  // The starting leaf pairs (neighbours of neighbours along the chain): test and write.
  void TestStartLeafPairs() {
    const SphereBvhNodePair* leaf_pairs = t_.self_leaf_pairs.data();
    const unsigned num_leaf_pairs = static_cast<unsigned>(t_.self_leaf_pairs.size());
    for (unsigned k = 0; k < num_leaf_pairs;) {
      const unsigned run = std::min(num_leaf_pairs - k, FreePairs());
      for (const unsigned end = k + run; k < end; ++k) {
        const std::uint32_t p = static_cast<std::uint32_t>(leaf_pairs[k]);
        const std::uint32_t q = static_cast<std::uint32_t>(leaf_pairs[k] >> 32);
        pairs_[count_] = {static_cast<int>(p >> 4), static_cast<int>(q >> 4)};
        count_ += Overlap(reinterpret_cast<const float*>(sphere_bytes_ + p),
                          reinterpret_cast<const float*>(sphere_bytes_ + q))
                      ? 1
                      : 0;
      }
      if (run == 0) {  // `pairs` is full: count only
        count_ +=
            Overlap(sphere_, NodePairFirst(leaf_pairs[k]), NodePairSecond(leaf_pairs[k])) ? 1 : 0;
        ++k;
      }
    }
  }

  // The starting node pairs into the ring, those that overlap; with the ring full, a pair is
  // finished depth first on the stack.
  void QueueStartPairs() {
    const SphereBvhNodePair* start = t_.self_pairs.data();
    const unsigned num_start = static_cast<unsigned>(t_.self_pairs.size());
    for (unsigned k = 0; k < num_start;) {
      const unsigned run = std::min(num_start - k, ring_size_ - (tail_ - head_));
      if (run == 0) {
        count_ = FindCollisionOnStack(t_, sphere_, start[k++], pairs_, capacity_, count_);
        continue;
      }
      for (const unsigned end = k + run; k < end; ++k) {
        ring_[tail_ & (ring_size_ - 1)] = start[k];
        tail_ += Overlaps(start[k]);
      }
    }
  }

  // Breadth first, in runs that cannot overflow either ring. A full small ring is drained;
  // with the main ring full, one pair is finished depth first on the stack.
  void DrainRing() {
    while (head_ != tail_) {
      const unsigned run = RunLength(tail_ - head_);
      if (run == 0) {  // the pair overlaps: the stack's first test repeats that
        count_ = FindCollisionOnStack(t_, sphere_, ring_[head_++ & (ring_size_ - 1)], pairs_,
                                      capacity_, count_);
        continue;
      }
      for (const unsigned end = head_ + run; head_ != end; ++head_) {
        Split(ring_[head_ & (ring_size_ - 1)]);
      }
    }
  }

  // The small pairs pushed: their leaf pairs tested four at a time.
  void DrainSmall() {
    while (small_head_ != small_tail_) {
      const unsigned run = std::min(small_tail_ - small_head_, FreePairs() / 4);
      if (run == 0) {
        TestSmallPair(small_ring_[small_head_++ & (small_size_ - 1)], true);
        continue;
      }
      for (const unsigned end = small_head_ + run; small_head_ != end; ++small_head_) {
        TestSmallPair(small_ring_[small_head_ & (small_size_ - 1)], false);
      }
    }
  }

 private:
  unsigned FreePairs() const { return static_cast<unsigned>(std::max(capacity_ - count_, 0)); }

  const SphereBvhTraversalNode& Record(std::uint32_t offset) const {
    return *reinterpret_cast<const SphereBvhTraversalNode*>(node_bytes_ + offset);
  }

  unsigned Overlaps(SphereBvhNodePair pq) const {
    return Overlap(
               reinterpret_cast<const float*>(sphere_bytes_ + static_cast<std::uint32_t>(pq)),
               reinterpret_cast<const float*>(sphere_bytes_ + static_cast<std::uint32_t>(pq >> 32)))
               ? 1u
               : 0u;
  }

  // One FindCollision step on a pair already found to overlap, with a node of more than two
  // links: split it and test its two children, keeping those that overlap; children with both
  // nodes small go to the small ring untested (their leaf pairs are tested there). A miss costs
  // one test and nothing else, as the pairs are tested where they are made. No branch depends
  // on a test, so successive tests overlap in the processor. Needs two free slots in each ring.
  void Split(SphereBvhNodePair pq) {
    const std::uint32_t p = static_cast<std::uint32_t>(pq);
    const std::uint32_t q = static_cast<std::uint32_t>(pq >> 32);
    // Split p (first) or q; the other keeps its half of the packed pair. Arithmetic, not a
    // branch: which one is split follows no pattern the processor could predict.
    const SphereBvhTraversalNode& np = Record(p);
    const SphereBvhTraversalNode& nq = Record(q);
    const unsigned first = DescendFirst(np.size, nq.size) ? 1u : 0u;
    const unsigned child_shift = 32 * (first ^ 1u);
    const std::uint64_t keep = pq & (std::uint64_t{0xffffffffu} << (32 * first));
    const unsigned keep_size =
        static_cast<unsigned>(np.size) ^
        ((static_cast<unsigned>(np.size) ^ static_cast<unsigned>(nq.size)) & (0u - first));
    const unsigned keep_small = keep_size <= kSmall ? 1u : 0u;
    const SphereBvhTraversalNode& split = Record(static_cast<std::uint32_t>(pq >> child_shift));
    const std::uint64_t left = keep | static_cast<std::uint64_t>(split.left_offset & ~15u)
                                          << child_shift;
    const std::uint64_t right = keep | static_cast<std::uint64_t>(split.right_offset & ~15u)
                                           << child_shift;
    const unsigned left_small = keep_small & split.left_offset;
    const unsigned right_small = keep_small & split.right_offset;
    ring_[tail_ & (ring_size_ - 1)] = left;
    tail_ += (left_small ^ 1u) & Overlaps(left);
    ring_[tail_ & (ring_size_ - 1)] = right;
    tail_ += (right_small ^ 1u) & Overlaps(right);
    small_ring_[small_tail_ & (small_size_ - 1)] = left;
    small_tail_ += left_small;
    small_ring_[small_tail_ & (small_size_ - 1)] = right;
    small_tail_ += right_small;
  }

  // The up to four leaf pairs (a, b), (a, b + 1), (a + 1, b), (a + 1, b + 1): those of `lanes`
  // that overlap are written (the tests are the single-pair test, without branches). Needs four
  // free slots in `pairs` unless `checked`.
  void TestLeaves(int a, int b, unsigned lanes, bool checked) {
    const float* sa = sphere_ + 4 * a;
    const float* sb = sphere_ + 4 * b;
    const unsigned hits = ((Overlap(sa, sb) ? 1u : 0u) | (Overlap(sa, sb + 4) ? 2u : 0u) |
                           (Overlap(sa + 4, sb) ? 4u : 0u) | (Overlap(sa + 4, sb + 4) ? 8u : 0u)) &
                          lanes;
    // Each pair as one 8-byte store: {a + i, b + j} is {a, b} plus the lane's {i, j}, and
    // the two ints add without carry between them (link indices are far below 2^31).
    static_assert(sizeof(LinkPair) == sizeof(std::uint64_t));
    const std::uint64_t base = std::bit_cast<std::uint64_t>(LinkPair{a, b});
    for (int lane = 0; lane < 4; ++lane) {
      const std::uint64_t value =
          base + std::bit_cast<std::uint64_t>(LinkPair{lane >> 1, lane & 1});
      if (!checked || count_ < capacity_) pairs_[count_] = std::bit_cast<LinkPair>(value);
      count_ += static_cast<int>(hits >> lane) & 1;
    }
  }

  // A pushed small pair of nodes (at most two links each, not neighbours).
  void TestSmallPair(SphereBvhNodePair pq, bool checked) {
    const SphereBvhTraversalNode& np = Record(static_cast<std::uint32_t>(pq));
    const SphereBvhTraversalNode& nq = Record(static_cast<std::uint32_t>(pq >> 32));
    TestLeaves(np.lo, nq.lo, (np.size == 2 ? 15u : 3u) & (nq.size == 2 ? 15u : 5u), checked);
  }

  // Runs of the ring that leave two free slots per pair in both rings.
  unsigned RunLength(unsigned available) {
    if (small_tail_ - small_head_ + 2 > small_size_) DrainSmall();
    const unsigned free_ring = (ring_size_ - (tail_ - head_)) / 2;
    const unsigned free_small = (small_size_ - (small_tail_ - small_head_)) / 2;
    return std::min(available, std::min(free_ring, free_small));
  }

  const SphereBvhTopology& t_;
  const float* sphere_;
  const char* sphere_bytes_;
  const char* node_bytes_;
  SphereBvhNodePair* ring_;
  SphereBvhNodePair* small_ring_;
  unsigned ring_size_, small_size_;
  unsigned head_ = 0, tail_ = 0, small_head_ = 0, small_tail_ = 0;
  LinkPair* pairs_;
  int capacity_;
  int count_ = 0;
};

}  // namespace

int FindSelfCollisions(const SphereBvhTopology& t, SphereBvhSpheres& spheres, LinkPair* pairs,
                       int capacity) {
  SelfCollisionTraversal traversal(t, spheres, pairs, capacity);
  traversal.TestStartLeafPairs();
  traversal.QueueStartPairs();
  traversal.DrainRing();
  traversal.DrainSmall();
  return traversal.count();
}

int FindSelfCollisionsAllPairs(const SphereBvhTopology& t, const SphereBvhSpheres& spheres,
                               LinkPair* pairs, int capacity) {
  const int n = t.num_leaves;
  const float* s = spheres.xyzr.data();
  int count = 0;
  for (int la = 0; la < n; ++la) {
    for (int lb = la + 2; lb < n; ++lb) {
      if (!OverlapScalar(s + 4 * la, s + 4 * lb)) continue;
      if (count < capacity) pairs[count] = {la, lb};
      ++count;
    }
  }
  return count;
}

}  // namespace microdex::thread
