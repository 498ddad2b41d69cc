#pragma once
// Reference knot geometries for tests and benchmarks, built from explicit parametrisations
// (not from any knot recognition code): torus knots, the figure-eight Lissajous curve, braid
// closures, overhand knots as tied on a standing part, connected sums by splicing, coils and
// ascending (unknotted) random walks. Closed curves are returned without repeating the first
// point; open threads are polylines whose ends are the free ends.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace microdex::knot::shapes {

using Curve = std::vector<Eigen::Vector3d>;

// Torus knot T(p, q): ((R + r cos q s) cos p s, (R + r cos q s) sin p s, -r sin q s), with
// the z component negated when `mirror`. Not mirrored, every crossing of its projection on
// the xy plane is positive (T(2, 3): the right-handed trefoil).
Curve TorusKnot(int p, int q, int samples, bool mirror = false, double big_r = 2.0,
                double small_r = 1.0);

// Figure-eight knot: ((2 + cos 2s) cos 3s, (2 + cos 2s) sin 3s, sin 4s).
Curve FigureEightCurve(int samples);

// Closure of a braid on `strands` strands around the z axis. word[k] = +i / -i is the
// generator sigma_i^(+-1) (1 <= i < strands) swapping strands i-1 and i; for +i the strand
// moving outwards passes over, a positive crossing seen from +z.
Curve BraidClosure(int strands, std::span<const int> word, int samples_per_generator = 24);

// Overhand knot as tied: a straight standing part, a loop crossing it, and the end passing
// through the loop `passes` times as a helix around the standing part (passes = 1:
// overhand, 2: double overhand). `right` picks the right-handed version (every crossing of
// its projection on the xy plane positive). Open thread with tails along -x and +x.
Curve OverhandAsTied(int passes, bool right);

// A closed knot opened at its node of largest x into a long knot: one tail runs above
// everything to the far left, the other straight to the far right (`tail_length` each).
Curve LongKnot(std::span<const Eigen::Vector3d> closed, double tail_length);

// Connected sum of two open threads whose ends leave along -x (first node) and +x (last
// node): b is moved to the right of a, its first node `gap` beyond a's last node.
Curve Splice(std::span<const Eigen::Vector3d> a, std::span<const Eigen::Vector3d> b, double gap);

// Polylines resampled at equal arc-length spacing (closed: the closing edge included).
Curve ResampleClosed(std::span<const Eigen::Vector3d> closed, double spacing);
Curve ResampleOpen(std::span<const Eigen::Vector3d> open, double spacing);
// Arc length of an open polyline.
double Length(std::span<const Eigen::Vector3d> open);

// Open helix (coil) of `turns` turns, radius and pitch given: an unknot whose projections
// have many crossings.
Curve Coil(int turns, double radius, double pitch, int samples_per_turn);

// Ascending random walk: a planar random walk of `steps` steps of length `step` whose height
// rises along the thread, with a vertical first and last segment: every closure outside is
// the unknot, whatever the crossings of its projection.
Curve AscendingRandomWalk(int steps, double step, double rise_per_step, std::uint64_t seed);

}  // namespace microdex::knot::shapes
