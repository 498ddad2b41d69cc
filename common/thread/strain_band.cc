#include "common/thread/strain_band.h"

#include <algorithm>
#include <cmath>

#include "common/thread/thread_model.h"

namespace microdex::thread {
namespace {

// Levenberg-Marquardt damping of the tridiagonal system, relative to its diagonal. A chain held
// straight between two grasped ends makes J W J^T singular (equal multipliers on every link move
// no free node); the damping keeps the solve finite there and changes the others by ~1e-4 of a
// Newton step (the next iteration corrects it).
constexpr double kDamping = 1e-4;
// Converged when no link is outside the band by more than this fraction of its rest length.
constexpr double kTolerance = 1e-4;
// No node moves by more than this fraction of the shortest rest length in one iteration (an
// infeasible band, e.g. the ends pulled apart beyond the band, must not fling nodes).
constexpr double kMaxMove = 0.5;
// Halvings of a Newton step tried before the solve gives up.
constexpr int kLineSearchSteps = 4;

// Link j's violation of the band relative to its rest length (0 inside the band).
double LinkViolation(const ThreadModel& model, double limit, const Eigen::Matrix3Xd& x, int j) {
  const double l2 = (x.col(j + 1) - x.col(j)).squaredNorm();
  const double r = model.rest_length_m[j];
  const double lo = (1.0 - limit) * r, hi = (1.0 + limit) * r;
  if (l2 >= lo * lo && l2 <= hi * hi) return 0.0;  // inside the band: no square root
  const double l = std::sqrt(l2);
  return std::max({l - hi, lo - l, 0.0}) / r;
}

}  // namespace

StrainBandScratch MakeStrainBandScratch(int num_links) {
  StrainBandScratch s;
  s.e = Eigen::Matrix3Xd::Zero(3, num_links);
  s.c = Eigen::VectorXd::Zero(num_links);
  s.diag = Eigen::VectorXd::Zero(num_links);
  s.off = Eigen::VectorXd::Zero(num_links);
  s.lambda = Eigen::VectorXd::Zero(num_links);
  s.work = Eigen::VectorXd::Zero(num_links);
  s.active = Eigen::VectorXi::Zero(num_links);
  s.dx = Eigen::Matrix3Xd::Zero(3, num_links + 1);
  s.violation = Eigen::VectorXd::Zero(num_links);
  s.nodes = Eigen::VectorXi::Zero(num_links + 1);
  s.window = Eigen::VectorXi::Zero(num_links);
  s.in_window = Eigen::VectorXi::Zero(num_links);
  s.listed = Eigen::VectorXi::Zero(num_links);
  s.merged = Eigen::VectorXi::Zero(num_links);
  s.dirty = Eigen::VectorXi::Zero(num_links + 1);
  s.dirty_flag = Eigen::VectorXi::Zero(num_links + 1);
  s.moved = Eigen::VectorXi::Zero(num_links + 1);
  s.moved_flag = Eigen::VectorXi::Zero(num_links + 1);
  s.x_before = Eigen::Matrix3Xd::Zero(3, num_links + 1);
  return s;
}

void StrainBandScratch::StartTracking() {
  tracking = true;
  num_listed = -1;
  for (int k = 0; k < num_dirty; ++k) dirty_flag[dirty[k]] = 0;
  num_dirty = 0;
  ClearMoved();
}

void StrainBandScratch::ClearMoved() {
  for (int k = 0; k < num_moved; ++k) moved_flag[moved[k]] = 0;
  num_moved = 0;
}

StrainBandResult ProjectStrainBand(const ThreadModel& model, const Eigen::VectorXd& inverse_mass,
                                   double limit, int max_iterations, Eigen::Matrix3Xd& x,
                                   StrainBandScratch& s) {
  StrainBandResult result;
  const int nl = model.num_links;
  const Eigen::VectorXd& w = inverse_mass;
  const bool incremental = s.tracking && s.num_listed >= 0;
  if (!incremental) s.active.setZero();
  const double max_move = kMaxMove * model.rest_length_m.minCoeff();
  // Link j at the current positions: its direction, constraint value, place in the active set
  // and violation (of the band, relative to the rest length). Links outside the band are pulled
  // to its nearer edge; links held in an earlier iteration keep their length. (Holding every
  // link at its length instead, so that a correction spreads over the whole chain: a granny
  // knot held at 20 mN reached 24 % strain.)
  auto classify = [&](int j, bool first) {
    const Eigen::Vector3d d = x.col(j + 1) - x.col(j);
    const double l2 = d.squaredNorm();
    const double r = model.rest_length_m[j];
    const double lo = (1.0 - limit) * r, hi = (1.0 + limit) * r;
    s.c[j] = 0.0;
    s.violation[j] = 0.0;
    // Inside the band (most links, most calls): no square root unless the link is held.
    if (l2 >= lo * lo && l2 <= hi * hi) {
      if (s.active[j] != 0) s.e.col(j) = d / std::sqrt(l2);
      return;
    }
    const double l = std::sqrt(l2);
    if (l > 0.0) s.e.col(j) = d / l;
    const double violation = std::max({l - hi, lo - l, 0.0});
    if (first) {
      if (violation > kTolerance * r) ++result.corrected_links;
      result.max_violation_m = std::max(result.max_violation_m, violation);
    }
    s.violation[j] = violation / r;
    if (!(l > 0.0) || w[j] + w[j + 1] == 0.0) {
      s.active[j] = 0;
    } else if (l > hi) {
      s.active[j] = 1;
      s.c[j] = l - hi;
    } else if (l < lo) {
      s.active[j] = -1;
      s.c[j] = l - lo;
    }
  };
  // A Newton step moves only the nodes of the links it holds; the links touching those nodes
  // (the window) are the only ones whose length changes, so after the first iteration only
  // they are classified again, and the line search measures only them against the unchanged
  // rest. The links that were ever held or outside the band are listed (ascending): every
  // other link is free, inside the band and has multiplier 0, so the solve, the release and
  // the largest violation visit only the list. Same arithmetic as visiting every link, in less
  // time: the band usually holds a few short runs of a long chain.
  int num_nodes = 0;   // s.nodes[0..num_nodes): the nodes the step moves, ascending
  int num_window = 0;  // s.window[0..num_window): the links touching them, ascending
  int num_listed = 0;  // s.listed[0..num_listed)
  // Merges the ascending links[0..count) into the list, classifying each of them. In the first
  // iteration (`first`) the listed links are classified too and only the links held or outside
  // the band stay listed; later, every listed link stays.
  auto merge = [&](const int* links, int count, bool first) {
    int a = 0, b = 0, m = 0;
    while (a < num_listed || b < count) {
      const int la = a < num_listed ? s.listed[a] : nl;
      const int lb = b < count ? links[b] : nl;
      const int j = std::min(la, lb);
      if (lb == j || first) classify(j, first);
      const bool was_listed = la == j;
      if (la == j) ++a;
      if (lb == j) ++b;
      if ((was_listed && !first) || s.active[j] != 0 || s.violation[j] > 0.0) s.merged[m++] = j;
    }
    std::swap(s.listed, s.merged);
    num_listed = m;
  };
  // The classification at the end of a call is that of the positions it leaves (a failed line
  // search's rounding aside, whose nodes are marked moved), so a tracked call keeps it.
  auto finish = [&]() {
    if (s.tracking) s.num_listed = num_listed;
    return result;
  };
  double worst = 0.0;
  for (int it = 0; it <= max_iterations; ++it) {
    if (it == 0 && !incremental) {
      for (int j = 0; j < nl; ++j) {
        classify(j, true);
        s.lambda[j] = 0.0;
        if (s.active[j] != 0 || s.violation[j] > 0.0) s.listed[num_listed++] = j;
      }
      for (int k = 0; k < s.num_dirty; ++k) s.dirty_flag[s.dirty[k]] = 0;
      s.num_dirty = 0;
    } else if (it == 0) {
      // The last call's list, released, and the links touching the nodes moved since (in
      // s.window, free until the first solve), classified again: every other link is still
      // free and inside the band.
      num_listed = s.num_listed;
      for (int k = 0; k < num_listed; ++k) {
        s.active[s.listed[k]] = 0;
        s.lambda[s.listed[k]] = 0.0;
      }
      std::sort(s.dirty.data(), s.dirty.data() + s.num_dirty);
      int count = 0;
      for (int k = 0; k < s.num_dirty; ++k) {
        const int i = s.dirty[k];
        s.dirty_flag[i] = 0;
        for (int j = std::max(0, i - 1); j <= std::min(nl - 1, i); ++j) {
          if (count == 0 || s.window[count - 1] < j) s.window[count++] = j;
        }
      }
      s.num_dirty = 0;
      merge(s.window.data(), count, true);
    } else {
      merge(s.window.data(), num_window, false);  // the window's links, classified again
    }
    worst = 0.0;
    for (int k = 0; k < num_listed; ++k) worst = std::max(worst, s.violation[s.listed[k]]);
    if (worst <= kTolerance || it == max_iterations) break;
    // (J W J^T + damping) lambda = -C over the active links; inactive links are identity rows
    // (lambda 0), so the tridiagonal system falls apart into the runs of consecutive active
    // links, each solved by the Thomas algorithm (symmetric, diagonally dominant: no pivoting
    // needed).
    num_nodes = 0;
    for (int k = 0; k < num_listed;) {
      const int j = s.listed[k];
      if (s.active[j] == 0) {
        s.lambda[j] = 0.0;
        ++k;
        continue;
      }
      const int start = j;
      int end = j;
      while (k < num_listed && s.listed[k] == end && s.active[end] != 0) {
        ++end;
        ++k;
      }
      for (int i = start; i < end; ++i) {
        s.diag[i] = (w[i] + w[i + 1]) * (1.0 + kDamping);
        s.off[i] = i + 1 < end ? -w[i + 1] * s.e.col(i).dot(s.e.col(i + 1)) : 0.0;
      }
      double pivot = s.diag[start];
      s.lambda[start] = -s.c[start] / pivot;
      s.work[start] = s.off[start] / pivot;
      for (int i = start + 1; i < end; ++i) {
        pivot = s.diag[i] - s.off[i - 1] * s.work[i - 1];
        if (!(pivot > 0.0)) return finish();
        s.work[i] = s.off[i] / pivot;
        s.lambda[i] = (-s.c[i] - s.off[i - 1] * s.lambda[i - 1]) / pivot;
      }
      for (int i = end - 2; i >= start; --i) s.lambda[i] -= s.work[i] * s.lambda[i + 1];
      for (int i = start; i <= end; ++i) s.nodes[num_nodes++] = i;  // the run's nodes
    }
    // The window: links touching a moved node, each once, ascending.
    num_window = 0;
    for (int k = 0; k < num_nodes; ++k) {
      for (int j = std::max(0, s.nodes[k] - 1); j <= std::min(nl - 1, s.nodes[k]); ++j) {
        if (num_window == 0 || s.window[num_window - 1] < j) s.window[num_window++] = j;
      }
    }
    // A link held inside the band whose multiplier would stretch it beyond its length at the
    // upper edge's side (or shorten it at the lower edge's) is let go from now on.
    for (int k = 0; k < num_listed; ++k) {
      const int j = s.listed[k];
      if ((s.active[j] == 1 || s.active[j] == -1) && s.c[j] == 0.0 &&
          s.active[j] * s.lambda[j] > 0.0) {
        s.active[j] = 0;
      }
    }
    // The move dx = W J^T lambda (zero off the moved nodes), at most max_move per node; then
    // halved until the largest violation decreases (a Newton step on strongly bent chains can
    // overshoot).
    double largest2 = 0.0;
    for (int k = 0; k < num_nodes; ++k) {
      const int i = s.nodes[k];
      Eigen::Vector3d dx = Eigen::Vector3d::Zero();
      if (i > 0) dx += s.lambda[i - 1] * s.e.col(i - 1);
      if (i < nl) dx -= s.lambda[i] * s.e.col(i);
      s.dx.col(i) = w[i] * dx;
      largest2 = std::max(largest2, s.dx.col(i).squaredNorm());
    }
    const double largest = std::sqrt(largest2);
    // The violation of the links outside the window, which the move leaves as they are.
    for (int k = 0; k < num_window; ++k) s.in_window[s.window[k]] = 1;
    double rest = 0.0;
    for (int k = 0; k < num_listed; ++k) {
      const int j = s.listed[k];
      if (s.in_window[j] == 0) rest = std::max(rest, s.violation[j]);
    }
    for (int k = 0; k < num_window; ++k) s.in_window[s.window[k]] = 0;
    double step = largest > max_move ? max_move / largest : 1.0;
    bool improved = false;
    if (s.tracking) {
      for (int k = 0; k < num_nodes; ++k) {
        const int i = s.nodes[k];
        if (s.moved_flag[i] != 0) continue;
        s.moved_flag[i] = 1;
        s.moved[s.num_moved++] = i;
        s.x_before.col(i) = x.col(i);
      }
    }
    for (int half = 0; half < kLineSearchSteps && !improved; ++half, step *= 0.5) {
      for (int k = 0; k < num_nodes; ++k) x.col(s.nodes[k]) += step * s.dx.col(s.nodes[k]);
      double trial = rest;
      for (int k = 0; k < num_window; ++k) {
        trial = std::max(trial, LinkViolation(model, limit, x, s.window[k]));
      }
      if (trial < worst) {
        improved = true;
      } else {
        for (int k = 0; k < num_nodes; ++k) x.col(s.nodes[k]) -= step * s.dx.col(s.nodes[k]);
      }
    }
    ++result.iterations;
    if (!improved) {
      // The moves taken back may leave the last bit changed.
      if (s.tracking) {
        for (int k = 0; k < num_nodes; ++k) s.MarkMoved(s.nodes[k]);
      }
      break;
    }
  }
  return finish();
}

}  // namespace microdex::thread
