#include "common/thread/thread_contacts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "common/geometry/segment_distance.h"
#include "common/thread/sphere_bvh.h"
#include "common/thread/strain_band.h"

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

// Closest points closer than this to a link end (in link parameter) are not interior.
constexpr double kInterior = 1e-6;
// The contact projection stops when no constraint is violated by more than this fraction of
// the diameter (or after kMaxProjectionSweeps). Link lengths take part in the first
// kStrainSweeps sweeps (a direct solve of all of them after each sweep over the contacts);
// the sweeps after those are contacts only, so that where a knot jams (contacts and the strain
// band cannot both hold within the step) the contacts win. Measured (README, Contact
// formulation): 32 of 48 keeps a granny knot held at 20 mN at 8 % strain where 16 of 32 left
// 19 %, and the stability map at 229 of 240 runs against 194.
constexpr double kProjectionTolerance = 0.005;
constexpr int kMaxProjectionSweeps = 48;
constexpr int kStrainSweeps = 32;
// Newton iterations of one direct strain-band solve (each a tridiagonal solve; 4 gave the
// same knots and 224 instead of 226 stable runs of the map).
constexpr int kStrainIterations = 8;

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

int FindCandidatePairs(const ThreadModel& model, ThreadWorkspace& w, ThreadState& state) {
  const Eigen::Matrix3Xd& x = state.x_W;
  RefitSphereBvh(model.bvh, x, model.bvh_inflate_m, w.spheres);
  const int capacity = model.contact_capacity;
  int found = FindSelfCollisions(model.bvh, w.spheres, w.pairs.data(), capacity);
  if (found > capacity) {
    ++state.status.contact_overflows;
    found = capacity;
  }
  state.status.num_candidate_pairs = found;
  return found;
}

int FindSweptPairs(const ThreadModel& model, const Eigen::Matrix3Xd& x0_W, double move_m,
                   ThreadWorkspace& w) {
  RefitSphereBvh(model.bvh, x0_W, model.bvh_inflate_m + move_m, w.spheres);
  const int capacity = model.contact_capacity;
  return std::min(capacity,
                  FindSelfCollisions(model.bvh, w.spheres, w.swept_pairs.data(), capacity));
}

void FindThreadContacts(const ThreadModel& model, std::span<const Collider> colliders,
                        ThreadWorkspace& w, ThreadState& state) {
  const Eigen::Matrix3Xd& x = state.x_W;
  const int capacity = model.contact_capacity;
  const int found = FindCandidatePairs(model, w, state);
  const double cutoff = model.def.contact_cutoff_m;
  int n_self = 0;
  for (int k = 0; k < found; ++k) {
    const LinkPair& pair = w.pairs[k];
    const Eigen::Vector3d a0 = x.col(pair.a);
    const Eigen::Vector3d a1 = x.col(pair.a + 1);
    const Eigen::Vector3d b0 = x.col(pair.b);
    const Eigen::Vector3d b1 = x.col(pair.b + 1);
    const geometry::SegmentClosest c = geometry::ClosestSegmentSegment(a0, a1, b0, b1);
    PairStart& start = w.pair_start[k];
    start.distance_m = c.distance_m;
    start.interior = c.distance_m > 0.0 && c.s > kInterior && c.s < 1.0 - kInterior &&
                     c.t > kInterior && c.t < 1.0 - kInterior;
    if (start.interior) start.n_W = (c.p - c.q) / c.distance_m;
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
      if (LinkColliderGapLowerBound(col, x.col(j), x.col(j + 1), model.radius_m) >= cutoff) {
        continue;
      }
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

Eigen::Vector3d CalcColliderLoad(const ThreadModel& model, const ThreadWorkspace& w,
                                 const ThreadState& state, int collider, int margin_links) {
  const Eigen::Matrix3Xd& x = state.x_W;
  // The stretch force along link j (node order), zero beyond the thread's ends.
  const auto pull = [&](int j) -> Eigen::Vector3d {
    if (j < 0 || j >= model.num_links) return Eigen::Vector3d::Zero();
    const Eigen::Vector3d e = x.col(j + 1) - x.col(j);
    const double l = e.norm();
    if (!(l > 0.0)) return Eigen::Vector3d::Zero();
    return (model.stretch_k_N_per_m[j] * (l - model.rest_length_m[j]) / l) * e;
  };
  const int m = std::max(margin_links, 0);
  Eigen::Vector3d f_W = Eigen::Vector3d::Zero();
  int first = 0, last = -1;  // the extended run being gathered (empty when last < first)
  const auto cut = [&] {
    if (last >= first) f_W += pull(last + 1) - pull(first - 1);
  };
  // The list holds each collider's contacts in link order (FindThreadContacts).
  for (int c = 0; c < w.num_object_contacts; ++c) {
    const ObjectContact& oc = w.object_contacts[c];
    if (oc.collider != collider) continue;
    const int a = std::max(oc.link - m, 0), b = std::min(oc.link + m, model.num_links - 1);
    if (last >= first && a <= last + 1) {
      last = std::max(last, b);
      continue;
    }
    cut();
    first = a;
    last = b;
  }
  cut();
  return f_W;
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
    // (5.9) along the pair normal, plus a force carried from the last step (a held knot).
    const double f =
        ContactForceMagnitude(def, sc.gap_m) + (c < w.num_self_carried ? w.self_carried_N[c] : 0.0);
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

void FindPairStarts(const ThreadModel& model, ThreadWorkspace& w, ThreadState& state) {
  const Eigen::Matrix3Xd& x = state.x_W;
  const int found = FindCandidatePairs(model, w, state);
  for (int k = 0; k < found; ++k) {
    const LinkPair& pair = w.pairs[k];
    const geometry::SegmentClosest c = geometry::ClosestSegmentSegment(
        x.col(pair.a), x.col(pair.a + 1), x.col(pair.b), x.col(pair.b + 1));
    PairStart& start = w.pair_start[k];
    start.distance_m = c.distance_m;
    start.interior = c.distance_m > 0.0 && c.s > kInterior && c.s < 1.0 - kInterior &&
                     c.t > kInterior && c.t < 1.0 - kInterior;
    if (start.interior) start.n_W = (c.p - c.q) / c.distance_m;
  }
}

ContactProjection ProjectContacts(const ThreadModel& model, std::span<const Collider> colliders,
                                  double strain_limit, const Eigen::Matrix3Xd& x0,
                                  ThreadWorkspace& w, ThreadState& state) {
  ContactProjection result;
  const ThreadDef& def = model.def;
  const double fraction = def.guard_fraction;
  if (fraction <= 0.0 && strain_limit <= 0.0) return result;
  Eigen::Matrix3Xd& x = state.x_W;
  const double min_dist = fraction * def.diameter_m;
  const double min_gap = (fraction - 1.0) * model.radius_m;
  const double tolerance = kProjectionTolerance * def.diameter_m;
  const double mu_self = def.friction_coefficient;
  const double mu_object = def.object_friction_coefficient;
  // A pair found satisfied after the last move of each of its nodes is satisfied still: it is
  // not tested again (the projection's result is the same, bit for bit, with or without the
  // skip). `clock` counts the tests; every move stamps its nodes with it.
  int clock = 0;
  w.node_moved_at.setZero();
  w.node_travel_m.setZero();
  // Moves the nodes so that sum_k g_k dx_k . dir = amount, each in proportion to g_k / m_k
  // (the smallest mass-weighted move); grasped nodes do not move.
  auto move = [&](const int* nodes, const double* g, int count, const Eigen::Vector3d& dir,
                  double amount) {
    double denom = 0.0;
    for (int k = 0; k < count; ++k) denom += g[k] * g[k] * InverseMass(model, w, nodes[k]);
    if (!(denom > 0.0)) return false;
    const double lambda = amount / denom;
    for (int k = 0; k < count; ++k) {
      const double step = lambda * g[k] * InverseMass(model, w, nodes[k]);
      x.col(nodes[k]) += step * dir;
      w.node_moved_at[nodes[k]] = clock;
      w.node_travel_m[nodes[k]] += std::abs(step);
      if (strain_limit > 0.0) w.strain_band.MarkMoved(nodes[k]);
    }
    return true;
  };
  // Coulomb friction of a normal correction (position level): the relative tangential
  // displacement of the contact points over the step is removed up to mu times the normal
  // correction (stick inside the cone, slide at its rim).
  auto rub = [&](const int* nodes, const double* g, int count, const Eigen::Vector3d& n,
                 double normal_m, double mu) {
    if (!(mu > 0.0)) return;
    Eigen::Vector3d rel = Eigen::Vector3d::Zero();
    for (int k = 0; k < count; ++k) rel += g[k] * (x.col(nodes[k]) - x0.col(nodes[k]));
    rel -= rel.dot(n) * n;
    const double slip = rel.norm();
    if (!(slip > 0.0)) return;
    move(nodes, g, count, rel / slip, -std::min(slip, mu * normal_m));
  };
  const int num_pairs = state.status.num_candidate_pairs;
  const int capacity = static_cast<int>(w.object_candidates.size());
  int num_candidates = 0;
  int sweep = 0;
  double residual = 0.0;
  if (strain_limit > 0.0) {
    for (int i = 0; i < model.num_nodes; ++i) w.inverse_mass[i] = InverseMass(model, w, i);
    w.strain_band.StartTracking();
  }
  for (; sweep < kMaxProjectionSweeps; ++sweep) {
    residual = 0.0;
    if (fraction > 0.0) {
      for (int k = 0; k < num_pairs; ++k) {
        const LinkPair& pair = w.pairs[k];
        const double travel = w.node_travel_m[pair.a] + w.node_travel_m[pair.a + 1] +
                              w.node_travel_m[pair.b] + w.node_travel_m[pair.b + 1];
        if (sweep > 0 && (w.pair_checked_at[k] >
                              std::max({w.node_moved_at[pair.a], w.node_moved_at[pair.a + 1],
                                        w.node_moved_at[pair.b], w.node_moved_at[pair.b + 1]}) ||
                          travel < w.pair_clear_m[k])) {
          continue;
        }
        ++clock;
        ++state.status.pair_tests;
        w.pair_checked_at[k] = clock;  // satisfied, unless a move below stamps its nodes
        const PairStart& before = w.pair_start[k];
        const geometry::SegmentClosest now = geometry::ClosestSegmentSegment(
            x.col(pair.a), x.col(pair.a + 1), x.col(pair.b), x.col(pair.b + 1));
        // No point of either link has moved further than its nodes' largest move: until their
        // summed travel exceeds the clearance, the links stay apart.
        w.pair_clear_m[k] = now.distance_m - min_dist + travel;
        const bool interior = before.interior && now.s > kInterior && now.s < 1.0 - kInterior &&
                              now.t > kInterior && now.t < 1.0 - kInterior;
        Eigen::Vector3d n;
        double separation;
        if (interior) {
          // Separation along the start-of-step normal: negative when the links crossed.
          n = before.n_W;
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
        const double deficit = min_dist - separation;
        residual = std::max(residual, deficit);
        w.pair_clear_m[k] = -std::numeric_limits<double>::infinity();
        const int nodes[4] = {pair.a, pair.a + 1, pair.b, pair.b + 1};
        const double g[4] = {1.0 - now.s, now.s, -(1.0 - now.t), -now.t};
        if (move(nodes, g, 4, n, deficit)) {
          ++result.contact_corrections;
          rub(nodes, g, 4, n, deficit, mu_self);
        }
      }
      // Objects: the first sweep tests every link against every collider and keeps the
      // links within a diameter of their constraint (or all, if more than the capacity); the
      // later sweeps visit only those.
      auto object = [&](int ci, int j) {
        // Far from the collider: neither a candidate nor violated (the bound is below the gap).
        if (sweep == 0 && LinkColliderGapLowerBound(colliders[ci], x.col(j), x.col(j + 1),
                                                    model.radius_m) >= min_gap + def.diameter_m) {
          return;
        }
        const LinkColliderGap gap =
            CalcLinkColliderGap(colliders[ci], x.col(j), x.col(j + 1), model.radius_m);
        if (sweep == 0 && gap.gap_m < min_gap + def.diameter_m) {
          if (num_candidates < capacity) {
            w.object_candidates[num_candidates] = LinkPair{j, ci};
          }
          ++num_candidates;
        }
        if (gap.gap_m >= min_gap) return;
        const double deficit = min_gap - gap.gap_m;
        residual = std::max(residual, deficit);
        const int nodes[2] = {j, j + 1};
        const double g[2] = {1.0 - gap.s, gap.s};
        if (move(nodes, g, 2, gap.n_W, deficit)) {
          ++result.contact_corrections;
          rub(nodes, g, 2, gap.n_W, deficit, mu_object);
        }
      };
      if (sweep == 0 || num_candidates > capacity) {
        for (int ci = 0; ci < static_cast<int>(colliders.size()); ++ci) {
          if (!colliders[ci].enabled) continue;
          for (int j = 0; j < model.num_links; ++j) {
            if (!ColliderIgnoresLink(colliders[ci], j)) object(ci, j);
          }
        }
      } else {
        // As for the pairs: a candidate found satisfied after its nodes' last moves is
        // satisfied still (the colliders do not move during the projection).
        for (int k = 0; k < num_candidates; ++k) {
          const LinkPair& c = w.object_candidates[k];
          if (sweep > 1 &&
              w.object_checked_at[k] > std::max(w.node_moved_at[c.a], w.node_moved_at[c.a + 1])) {
            continue;
          }
          ++clock;
          w.object_checked_at[k] = clock;
          object(c.b, c.a);
        }
      }
    }
    if (strain_limit > 0.0 && sweep < kStrainSweeps) {
      // Link lengths into [1 - limit, 1 + limit] rest lengths, all links at once.
      StrainBandScratch& band_scratch = w.strain_band;
      const StrainBandResult band = ProjectStrainBand(model, w.inverse_mass, strain_limit,
                                                      kStrainIterations, x, band_scratch);
      ++clock;
      for (int k = 0; k < band_scratch.num_moved; ++k) {
        const int i = band_scratch.moved[k];
        if ((x.col(i).array() != band_scratch.x_before.col(i).array()).any()) {
          w.node_moved_at[i] = clock;
          w.node_travel_m[i] += (x.col(i) - band_scratch.x_before.col(i)).norm();
        }
      }
      band_scratch.ClearMoved();
      result.strain_corrections += band.corrected_links;
      residual = std::max(residual, band.max_violation_m);
    }
    if (residual <= tolerance) {
      ++sweep;
      break;
    }
  }
  w.projection_sweeps = sweep;
  w.projection_residual_m = residual;
  return result;
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
