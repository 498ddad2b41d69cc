#include "tests/support/knot_shapes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "common/base/check.h"
#include "common/knot/stitch_knot_shapes.h"

namespace microdex::knot::shapes {
namespace {

constexpr double kPi = std::numbers::pi;

// Smoothstep for the strand exchanges of a braid generator.
double Smooth(double u) { return u * u * (3.0 - 2.0 * u); }

}  // namespace

Curve TorusKnot(int p, int q, int samples, bool mirror, double big_r, double small_r) {
  MICRODEX_CHECK(samples >= 8);
  Curve c(samples);
  for (int k = 0; k < samples; ++k) {
    const double s = 2.0 * kPi * k / samples;
    const double rho = big_r + small_r * std::cos(q * s);
    c[k] = {rho * std::cos(p * s), rho * std::sin(p * s),
            (mirror ? 1.0 : -1.0) * small_r * std::sin(q * s)};
  }
  return c;
}

Curve FigureEightCurve(int samples) {
  MICRODEX_CHECK(samples >= 8);
  Curve c(samples);
  for (int k = 0; k < samples; ++k) {
    const double s = 2.0 * kPi * k / samples;
    const double rho = 2.0 + std::cos(2.0 * s);
    c[k] = {rho * std::cos(3.0 * s), rho * std::sin(3.0 * s), std::sin(4.0 * s)};
  }
  return c;
}

Curve BraidClosure(int strands, std::span<const int> word, int samples_per_generator) {
  MICRODEX_CHECK(strands >= 1 && !word.empty() && samples_per_generator % 2 == 0);
  const int g = static_cast<int>(word.size());
  // Strand at slot j sits at radius kR0 + j; over/under by +-kLift in z mid-exchange.
  constexpr double kR0 = 3.0;
  constexpr double kLift = 0.35;
  // Track which physical strand occupies which slot; sample each slot's path per generator.
  // paths[strand] lists (phi, radius, z) samples; strands are then chained by the
  // permutation into one closed curve.
  std::vector<int> slot_of(strands);
  for (int j = 0; j < strands; ++j) slot_of[j] = j;
  std::vector<Curve> pieces(strands);  // piece per starting slot
  std::vector<int> strand_at_slot(strands);
  for (int j = 0; j < strands; ++j) strand_at_slot[j] = j;
  for (int k = 0; k < g; ++k) {
    const int gen = std::abs(word[k]);
    MICRODEX_CHECK(gen >= 1 && gen < strands);
    const int lo = gen - 1;
    for (int step = 0; step < samples_per_generator; ++step) {
      // Half-step offset: no sample at mid-exchange, where two strands would project
      // onto the same point.
      const double u = (step + 0.5) / samples_per_generator;
      const double phi = 2.0 * kPi * (k + u) / g;
      for (int slot = 0; slot < strands; ++slot) {
        const int strand = strand_at_slot[slot];
        double radius = kR0 + slot;
        double z = 0.0;
        if (slot == lo || slot == lo + 1) {
          const bool outward = slot == lo;
          radius = kR0 + lo + (outward ? Smooth(u) : 1.0 - Smooth(u));
          // The outward strand passes over for a positive generator.
          const bool over = outward == (word[k] > 0);
          z = (over ? kLift : -kLift) * std::sin(kPi * u);
        }
        pieces[strand].push_back({radius * std::cos(phi), radius * std::sin(phi), z});
      }
    }
    std::swap(strand_at_slot[lo], strand_at_slot[lo + 1]);
  }
  // After the word, strand s ends at slot `end_slot[s]` and continues as the strand that
  // started in that slot.
  std::vector<int> end_slot(strands);
  for (int slot = 0; slot < strands; ++slot) end_slot[strand_at_slot[slot]] = slot;
  Curve curve;
  int strand = 0;
  for (int visited = 0; visited < strands; ++visited) {
    curve.insert(curve.end(), pieces[strand].begin(), pieces[strand].end());
    strand = end_slot[strand];
    if (strand == 0) {
      MICRODEX_CHECK(visited == strands - 1);  // one component: a knot
      break;
    }
  }
  return curve;
}

Curve OverhandAsTied(int passes, bool right) {
  MICRODEX_CHECK(passes >= 1);
  // Projected on the xy plane: the loop's crossing with the standing part has sign
  // sign(loop over) and each helix crossing has sign -helix; right-handed: all positive.
  const double loop_z = right ? 0.3 : -0.3;
  const double helix = right ? -1.0 : 1.0;
  Curve c;
  // Standing part along +x, then the loop (y > 0) crossing back over / under it at x = -2.1.
  for (double x = -6.0; x < 2.0; x += 0.25) c.push_back({x, 0.0, 0.0});
  // (The crossing at x = -2.1, y = 0 lies inside edges of both strands.)
  const Curve loop = {{2.0, 0.0, 0.0},
                      {2.6, 1.2, 0.0},
                      {2.0, 2.6, 0.0},
                      {0.5, 3.2, 0.0},
                      {-1.0, 3.1, 0.0},
                      {-2.0, 2.4, 0.0},
                      {-2.2, 1.2, 0.0},
                      {-2.1, 0.4, 0.5 * loop_z},
                      {-2.1, 0.1, loop_z},
                      {-2.1, -0.2, loop_z},
                      {-2.1, -0.5, 0.5 * loop_z},
                      {-1.9, -1.2, 0.0},
                      {-1.5, -0.9, 0.0}};
  c.insert(c.end(), loop.begin(), loop.end());
  // The end passes through the loop: a helix of radius 0.6 around the standing part.
  const int samples = 48 * passes;
  for (int k = 0; k <= samples; ++k) {
    // A small phase keeps samples off the standing part's line in projection.
    const double theta = 2.0 * kPi * passes * k / samples + 0.05;
    c.push_back({-1.0 + 2.0 * k / samples, -0.6 * std::cos(theta), helix * 0.6 * std::sin(theta)});
  }
  for (const Eigen::Vector3d& p : Curve{{1.5, -0.9, 0.0}, {2.2, -1.6, 0.0}, {3.5, -2.0, 0.0}}) {
    c.push_back(p);
  }
  for (double x = 4.0; x <= 8.0; x += 0.25) c.push_back({x, -2.0, 0.0});
  return c;
}

Curve LongKnot(std::span<const Eigen::Vector3d> closed, double tail_length) {
  const int n = static_cast<int>(closed.size());
  MICRODEX_CHECK(n >= 4);
  Eigen::AlignedBox3d box;
  int i_max = 0;
  for (int i = 0; i < n; ++i) {
    box.extend(closed[i]);
    if (closed[i].x() > closed[i_max].x()) i_max = i;
  }
  const double margin = 0.3 * box.sizes().maxCoeff();
  const double x_right = box.max().x() + margin;
  const double z_top = box.max().z() + margin;
  const double x_left = box.min().x() - margin;
  const Eigen::Vector3d& a = closed[(i_max + 1) % n];
  const Eigen::Vector3d& b = closed[(i_max + n - 1) % n];
  Curve c;
  // Left tail (reversed path from a): far left above everything, over the top, down to a.
  c.push_back({x_left - tail_length, a.y(), z_top});
  c.push_back({x_left, a.y(), z_top});
  c.push_back({x_right, a.y(), z_top});
  c.push_back({x_right, a.y(), a.z()});
  for (int k = 1; k < n; ++k) c.push_back(closed[(i_max + k) % n]);
  c.push_back({x_right, b.y(), b.z()});
  c.push_back({x_right + tail_length, b.y(), b.z()});
  return c;
}

Curve Splice(std::span<const Eigen::Vector3d> a, std::span<const Eigen::Vector3d> b, double gap) {
  MICRODEX_CHECK(!a.empty() && !b.empty());
  Eigen::AlignedBox3d box_a;
  for (const auto& p : a) box_a.extend(p);
  Eigen::AlignedBox3d box_b;
  for (const auto& p : b) box_b.extend(p);
  // b's first node `gap` right of a's last node, and all of b right of all of a.
  Eigen::Vector3d shift = a.back() + Eigen::Vector3d(gap, 0, 0) - b.front();
  shift.x() = std::max(shift.x(), box_a.max().x() + gap - box_b.min().x());
  Curve c(a.begin(), a.end());
  const Eigen::Vector3d joint = b.front() + shift;
  if (joint.x() > a.back().x() + gap) c.push_back({joint.x() - gap, a.back().y(), a.back().z()});
  for (const auto& p : b) c.push_back(p + shift);
  return c;
}

double Length(std::span<const Eigen::Vector3d> open) { return knot::PolylineLength(open); }

Curve ResampleOpen(std::span<const Eigen::Vector3d> open, double spacing) {
  MICRODEX_CHECK(open.size() >= 2 && spacing > 0);
  return knot::ResampleByArcLength(
      open, std::max(1, static_cast<int>(std::round(Length(open) / spacing))));
}

Curve ResampleClosed(std::span<const Eigen::Vector3d> closed, double spacing) {
  Curve loop(closed.begin(), closed.end());
  loop.push_back(closed.front());
  Curve c = ResampleOpen(loop, spacing);
  c.pop_back();  // the first point again
  return c;
}

Curve Coil(int turns, double radius, double pitch, int samples_per_turn) {
  Curve c;
  const int samples = turns * samples_per_turn;
  for (int k = 0; k <= samples; ++k) {
    const double theta = 2.0 * kPi * k / samples_per_turn;
    c.push_back({radius * std::cos(theta), radius * std::sin(theta), pitch * theta / (2.0 * kPi)});
  }
  return c;
}

Curve AscendingRandomWalk(int steps, double step, double rise_per_step, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> turn(0.0, 0.6);
  Curve c;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double heading = 0.0;
  c.push_back(p - Eigen::Vector3d(0, 0, 5.0 * step));
  c.push_back(p);
  for (int k = 0; k < steps; ++k) {
    heading += turn(rng);
    // Stay within a disc so the walk crosses itself often.
    const double r = std::hypot(p.x(), p.y());
    if (r > 0.15 * step * std::sqrt(steps) * 3.0) heading = std::atan2(-p.y(), -p.x());
    p += Eigen::Vector3d(step * std::cos(heading), step * std::sin(heading), rise_per_step);
    c.push_back(p);
  }
  c.push_back(p + Eigen::Vector3d(0, 0, 5.0 * step));
  return c;
}

}  // namespace microdex::knot::shapes
