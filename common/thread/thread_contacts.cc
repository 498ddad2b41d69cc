#include "common/thread/thread_contacts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "common/geometry/segment_distance.h"
#include "common/thread/sphere_bvh.h"

namespace microdex::thread {
namespace {

// exp() argument cap: the exponential law grows without bound with overlap; the guard keeps
// overlaps small, this only keeps the arithmetic finite.
constexpr double kMaxExponent = 30.0;

// A unit vector normal to both link directions, for links whose centrelines touch exactly.
Eigen::Vector3d FallbackNormal(const Eigen::Vector3d& da, const Eigen::Vector3d& db) {
  Eigen::Vector3d n = da.cross(db);
  if (n.squaredNorm() > 0.0) return n.normalized();
  const Eigen::Vector3d axis =
      std::abs(da.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  n = da.cross(axis);
  return n.squaredNorm() > 0.0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
}

double InverseMass(const ThreadModel& model, const ThreadWorkspace& w, int node) {
  return w.grasp_slot[node] >= 0 ? 0.0 : 1.0 / model.mass_kg[node];
}

}  // namespace

double ContactForceMagnitude(const ThreadDef& def, double gap_m) {
  if (gap_m >= def.contact_cutoff_m) return 0.0;
  const double e = std::min(-gap_m / def.contact_decay_m, kMaxExponent);
  return def.contact_force_N *
         (std::exp(e) - std::exp(-def.contact_cutoff_m / def.contact_decay_m));
}

double ContactStiffness(const ThreadDef& def, double gap_m) {
  if (gap_m >= def.contact_cutoff_m) return 0.0;
  const double e = std::min(-gap_m / def.contact_decay_m, kMaxExponent);
  return def.contact_force_N / def.contact_decay_m * std::exp(e);
}

void FindThreadContacts(const ThreadModel& model, std::span<const Collider> colliders,
                        ThreadWorkspace& w, ThreadState& state) {
  const Eigen::Matrix3Xd& x = state.x_W;
  RefitSphereBvh(model.bvh, x, model.bvh_inflate_m, w.spheres);
  const int capacity = model.contact_capacity;
  int found = FindSelfCollisions(model.bvh, w.spheres, w.pairs.data(), capacity);
  if (found > capacity) {
    ++state.status.contact_overflows;
    found = capacity;
  }
  state.status.num_candidate_pairs = found;
  const double cutoff = model.def.contact_cutoff_m;
  int n_self = 0;
  for (int k = 0; k < found; ++k) {
    const LinkPair& pair = w.pairs[k];
    const Eigen::Vector3d a0 = x.col(pair.a);
    const Eigen::Vector3d a1 = x.col(pair.a + 1);
    const Eigen::Vector3d b0 = x.col(pair.b);
    const Eigen::Vector3d b1 = x.col(pair.b + 1);
    const geometry::SegmentClosest c = geometry::ClosestSegmentSegment(a0, a1, b0, b1);
    const double gap = c.distance_m - 2.0 * model.radius_m;
    if (gap >= cutoff) continue;
    SelfContact& sc = w.self_contacts[n_self++];
    sc.link_a = pair.a;
    sc.link_b = pair.b;
    sc.s = c.s;
    sc.t = c.t;
    sc.gap_m = gap;
    sc.n_W = c.distance_m > 0.0 ? Eigen::Vector3d((c.p - c.q) / c.distance_m)
                                : FallbackNormal(a1 - a0, b1 - b0);
  }
  w.num_self_contacts = n_self;
  int n_obj = 0;
  for (int ci = 0; ci < static_cast<int>(colliders.size()); ++ci) {
    const Collider& col = colliders[ci];
    if (!col.enabled) continue;
    for (int j = 0; j < model.num_links; ++j) {
      if (ColliderIgnoresLink(col, j)) continue;
      const LinkColliderGap g = CalcLinkColliderGap(col, x.col(j), x.col(j + 1), model.radius_m);
      if (g.gap_m >= cutoff) continue;
      if (n_obj >= capacity) {
        ++state.status.contact_overflows;
        break;
      }
      ObjectContact& oc = w.object_contacts[n_obj++];
      oc.link = j;
      oc.collider = ci;
      oc.s = g.s;
      oc.gap_m = g.gap_m;
      oc.n_W = g.n_W;
    }
  }
  w.num_object_contacts = n_obj;
  state.status.num_self_contacts = n_self;
  state.status.num_object_contacts = n_obj;
}

void AddContactForces(const ThreadModel& model, ThreadWorkspace& w, Eigen::Matrix3Xd& f_W,
                      bool with_stiffness, int exact_pairs) {
  const ThreadDef& def = model.def;
  if (with_stiffness) {
    w.k_contact.setZero();
    w.c_contact_N_s_per_m.setZero();
  }
  auto add_node = [&](int node, double weight, double f, double k, const Eigen::Vector3d& n,
                      double bound_factor) {
    f_W.col(node) += (weight * f) * n;
    if (!with_stiffness || bound_factor == 0.0) return;
    const Eigen::Matrix3d nn = n * n.transpose();
    Eigen::Map<Eigen::Matrix3d>(w.k_contact.col(node).data()) +=
        (bound_factor * std::abs(weight) * k) * nn;
    w.c_contact_N_s_per_m[node] += std::abs(weight) * def.contact_damping_N_s_per_m;
  };
  for (int c = 0; c < w.num_self_contacts; ++c) {
    const SelfContact& sc = w.self_contacts[c];
    const double f = ContactForceMagnitude(def, sc.gap_m);  // (5.9) along the pair normal
    const double k = ContactStiffness(def, sc.gap_m);
    // Weights g = (1-s, s, -(1-t), -t) map node motion to gap change; g g^T <= 2 diag(|g|)
    // because sum |g| = 2, hence the factor 2 in the diagonal bound. A pair coupled exactly
    // contributes its force only here: the step adds its k g g^T and damping itself.
    const double factor = c < exact_pairs ? 0.0 : 2.0;
    add_node(sc.link_a, 1.0 - sc.s, f, k, sc.n_W, factor);
    add_node(sc.link_a + 1, sc.s, f, k, sc.n_W, factor);
    add_node(sc.link_b, -(1.0 - sc.t), f, k, sc.n_W, factor);
    add_node(sc.link_b + 1, -sc.t, f, k, sc.n_W, factor);
  }
  for (int c = 0; c < w.num_object_contacts; ++c) {
    const ObjectContact& oc = w.object_contacts[c];
    const double f = ContactForceMagnitude(def, oc.gap_m);
    const double k = ContactStiffness(def, oc.gap_m);
    add_node(oc.link, 1.0 - oc.s, f, k, oc.n_W, 1.0);
    add_node(oc.link + 1, oc.s, f, k, oc.n_W, 1.0);
  }
}

int ApplyNonPenetrationGuard(const ThreadModel& model, std::span<const Collider> colliders,
                             double h, ThreadWorkspace& w, ThreadState& state) {
  const double fraction = model.def.guard_fraction;
  if (fraction <= 0.0) return 0;
  Eigen::Matrix3Xd& x = state.x_W;
  const Eigen::Matrix3Xd& x0 = w.x_prev_W;
  const double min_dist = fraction * model.def.diameter_m;
  // Interior closest points: the sign of the separation along the old normal is meaningful.
  constexpr double kInterior = 1e-6;
  int corrections = 0;
  auto push = [&](const int* nodes, const double* g, int count, const Eigen::Vector3d& n,
                  double deficit) {
    double denom = 0.0;
    for (int k = 0; k < count; ++k) denom += g[k] * g[k] * InverseMass(model, w, nodes[k]);
    if (!(denom > 0.0)) return;
    const double lambda = deficit / denom;
    for (int k = 0; k < count; ++k) {
      const Eigen::Vector3d dx = (lambda * g[k] * InverseMass(model, w, nodes[k])) * n;
      x.col(nodes[k]) += dx;
      state.v_W.col(nodes[k]) += dx / h;
    }
    ++corrections;
  };
  const int num_pairs = state.status.num_candidate_pairs;
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 0; k < num_pairs; ++k) {
      const LinkPair& pair = w.pairs[k];
      const geometry::SegmentClosest now = geometry::ClosestSegmentSegment(
          x.col(pair.a), x.col(pair.a + 1), x.col(pair.b), x.col(pair.b + 1));
      const geometry::SegmentClosest before = geometry::ClosestSegmentSegment(
          x0.col(pair.a), x0.col(pair.a + 1), x0.col(pair.b), x0.col(pair.b + 1));
      const bool interior = now.s > kInterior && now.s < 1.0 - kInterior && now.t > kInterior &&
                            now.t < 1.0 - kInterior && before.s > kInterior &&
                            before.s < 1.0 - kInterior && before.t > kInterior &&
                            before.t < 1.0 - kInterior && before.distance_m > 0.0;
      Eigen::Vector3d n;
      double separation;
      if (interior) {
        // Separation along the start-of-step normal: negative when the links crossed.
        n = (before.p - before.q) / before.distance_m;
        separation = (now.p - now.q).dot(n);
        if (separation >= min_dist) continue;
        if (separation >= 0.0 && now.distance_m >= min_dist) continue;
      } else {
        if (now.distance_m >= min_dist) continue;
        n = now.distance_m > 0.0 ? Eigen::Vector3d((now.p - now.q) / now.distance_m)
                                 : FallbackNormal(x.col(pair.a + 1) - x.col(pair.a),
                                                  x.col(pair.b + 1) - x.col(pair.b));
        separation = now.distance_m;
      }
      const int nodes[4] = {pair.a, pair.a + 1, pair.b, pair.b + 1};
      const double g[4] = {1.0 - now.s, now.s, -(1.0 - now.t), -now.t};
      push(nodes, g, 4, n, min_dist - separation);
    }
    for (int ci = 0; ci < static_cast<int>(colliders.size()); ++ci) {
      const Collider& col = colliders[ci];
      if (!col.enabled) continue;
      const double min_gap = (fraction - 1.0) * model.radius_m;
      for (int j = 0; j < model.num_links; ++j) {
        if (ColliderIgnoresLink(col, j)) continue;
        const LinkColliderGap gap =
            CalcLinkColliderGap(col, x.col(j), x.col(j + 1), model.radius_m);
        if (gap.gap_m >= min_gap) continue;
        const int nodes[2] = {j, j + 1};
        const double g[2] = {1.0 - gap.s, gap.s};
        push(nodes, g, 2, gap.n_W, min_gap - gap.gap_m);
      }
    }
  }
  return corrections;
}

double CalcMinNonAdjacentDistance(const ThreadModel& model, const Eigen::Matrix3Xd& x_W) {
  double best = std::numeric_limits<double>::infinity();
  for (int a = 0; a < model.num_links; ++a) {
    for (int b = a + 2; b < model.num_links; ++b) {
      const geometry::SegmentClosest c =
          geometry::ClosestSegmentSegment(x_W.col(a), x_W.col(a + 1), x_W.col(b), x_W.col(b + 1));
      best = std::min(best, c.distance_m);
    }
  }
  return best;
}

}  // namespace microdex::thread
