// RecognizeKnot / AnalyzeKnot / CalcKnotPlacement on threads built independently of the
// recogniser (common/thread/knot_shapes: parametric curves, braid closures, overhands as
// tied), with the chirality of each reference checked here by brute-force crossing signs, and
// robustness to rigid motions, scale, 1 % noise, projection seeds and where the ends lie.
#include "common/knot/recognition.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "tests/support/knot_shapes.h"

namespace microdex::knot {
namespace {

using shapes::Curve;

// Thread diameter of 10-0 nylon; nodes are one diameter apart.
constexpr double kDiameter_m = 3e-5;

// Signs of the crossings of the xy projection of an open or closed polyline, by brute force
// (an independent oracle for chirality: a reduced alternating diagram whose crossings are
// all positive is a positive knot).
std::vector<int> CrossingSignsAlongZ(const Curve& c, bool closed) {
  const int n = static_cast<int>(c.size());
  const int edges = closed ? n : n - 1;
  std::vector<int> signs;
  for (int i = 0; i < edges; ++i) {
    for (int j = i + 2; j < edges; ++j) {
      if (closed && i == 0 && j == n - 1) continue;
      const Eigen::Vector3d a = c[i], b = c[(i + 1) % n], p = c[j], q = c[(j + 1) % n];
      auto orient = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                       const Eigen::Vector3d& w) {
        return (v.x() - u.x()) * (w.y() - u.y()) - (v.y() - u.y()) * (w.x() - u.x());
      };
      const double o1 = orient(a, b, p), o2 = orient(a, b, q);
      const double o3 = orient(p, q, a), o4 = orient(p, q, b);
      if (o1 * o2 >= 0 || o3 * o4 >= 0) continue;
      const double t = o3 / (o3 - o4);
      const double s = o1 / (o1 - o2);
      const double z_ab = a.z() + t * (b.z() - a.z());
      const double z_pq = p.z() + s * (q.z() - p.z());
      const Eigen::Vector2d d_ab = (b - a).head<2>(), d_pq = (q - p).head<2>();
      const Eigen::Vector2d over = z_ab > z_pq ? d_ab : d_pq;
      const Eigen::Vector2d under = z_ab > z_pq ? d_pq : d_ab;
      signs.push_back(over.x() * under.y() - over.y() * under.x() > 0 ? 1 : -1);
    }
  }
  return signs;
}

// An open thread at real scale: resampled at `spacing` (shape units), scaled so that the
// spacing is one thread diameter.
Curve ToThread(const Curve& open, double spacing) {
  Curve c = shapes::ResampleOpen(open, spacing);
  for (auto& p : c) p *= kDiameter_m / spacing;
  return c;
}

Curve LongThread(const Curve& closed, double spacing = 0.1) {
  return ToThread(shapes::LongKnot(closed, 3.0), spacing);
}

Curve Braid(int strands, std::vector<int> word) { return shapes::BraidClosure(strands, word); }

struct Case {
  const char* name;
  Curve thread;
  KnotType expected;
};

std::vector<Case> ReferenceCases() {
  const Curve right = shapes::TorusKnot(2, 3, 400);
  const Curve left = shapes::TorusKnot(2, 3, 400, true);
  const Curve five_one = shapes::TorusKnot(2, 5, 500);
  const Curve five_one_mirror = shapes::TorusKnot(2, 5, 500, true);
  const Curve right_long = shapes::LongKnot(right, 3.0);
  const Curve left_long = shapes::LongKnot(left, 3.0);
  const Curve five_one_long = shapes::LongKnot(five_one, 3.0);
  const Curve five_one_mirror_long = shapes::LongKnot(five_one_mirror, 3.0);
  const Curve double_right = shapes::OverhandAsTied(2, true);
  const Curve single_right = shapes::OverhandAsTied(1, true);
  const Curve single_left = shapes::OverhandAsTied(1, false);
  auto splice = [](const Curve& a, const Curve& b) {
    return ToThread(shapes::Splice(a, b, 2.0), 0.1);
  };
  return {
      {"torus trefoil", LongThread(right), KnotType::kOverhandRight},
      {"mirrored torus trefoil", LongThread(left), KnotType::kOverhandLeft},
      {"figure-eight curve", LongThread(shapes::FigureEightCurve(400)), KnotType::kFigureEight},
      {"braid figure-eight", LongThread(Braid(3, {1, -2, 1, -2})), KnotType::kFigureEight},
      {"torus 5_1", LongThread(five_one), KnotType::kDoubleOverhand},
      {"mirrored torus 5_1", LongThread(five_one_mirror), KnotType::kDoubleOverhand},
      {"braid 5_2 (three-twist knot)", LongThread(Braid(3, {1, 1, 1, 2, -1, 2})),
       KnotType::kUnknown},
      {"braid 6_1 (stevedore)", LongThread(Braid(4, {1, 1, 2, -1, -3, 2, -3})), KnotType::kUnknown},
      {"torus 7_1", LongThread(shapes::TorusKnot(2, 7, 700)), KnotType::kUnknown},
      {"granny right", splice(right_long, right_long), KnotType::kGranny},
      {"granny left", splice(left_long, left_long), KnotType::kGranny},
      {"square", splice(right_long, left_long), KnotType::kSquare},
      {"square other order", splice(left_long, right_long), KnotType::kSquare},
      {"surgeons", splice(five_one_long, left_long), KnotType::kSurgeons},
      {"surgeons mirrored", splice(five_one_mirror_long, right_long), KnotType::kSurgeons},
      {"surgeon-like granny", splice(five_one_long, right_long), KnotType::kUnknown},
      {"braid granny", LongThread(Braid(3, {1, 1, 1, 2, 2, 2})), KnotType::kGranny},
      {"braid square", LongThread(Braid(3, {1, 1, 1, -2, -2, -2})), KnotType::kSquare},
      {"braid surgeons", LongThread(Braid(3, {1, 1, 1, 1, 1, -2, -2, -2})), KnotType::kSurgeons},
      {"overhand tied right", ToThread(single_right, 0.1), KnotType::kOverhandRight},
      {"overhand tied left", ToThread(single_left, 0.1), KnotType::kOverhandLeft},
      {"double overhand tied right", ToThread(double_right, 0.1), KnotType::kDoubleOverhand},
      {"double overhand tied left", ToThread(shapes::OverhandAsTied(2, false), 0.1),
       KnotType::kDoubleOverhand},
      {"surgeons tied", splice(double_right, single_left), KnotType::kSurgeons},
      {"surgeon-like granny tied", splice(double_right, single_right), KnotType::kUnknown},
      {"square tied", splice(single_left, single_right), KnotType::kSquare},
      {"granny tied", splice(single_right, single_right), KnotType::kGranny},
      {"straight", ToThread({{0, 0, 0}, {10, 0, 0}}, 0.1), KnotType::kNone},
      {"coil", ToThread(shapes::Coil(15, 1.0, 0.4, 40), 0.1), KnotType::kNone},
      {"messy unknot 1", ToThread(shapes::AscendingRandomWalk(300, 0.5, 0.02, 1), 0.1),
       KnotType::kNone},
      {"messy unknot 2", ToThread(shapes::AscendingRandomWalk(300, 0.5, 0.02, 2), 0.1),
       KnotType::kNone},
  };
}

TEST(KnotRecognitionTest, NamesAreTheCommandLineWords) {
  const std::vector<std::pair<KnotType, const char*>> words = {
      {KnotType::kNone, "none"},
      {KnotType::kOverhandLeft, "overhand-left"},
      {KnotType::kOverhandRight, "overhand-right"},
      {KnotType::kDoubleOverhand, "double-overhand"},
      {KnotType::kFigureEight, "figure-eight"},
      {KnotType::kSquare, "square"},
      {KnotType::kGranny, "granny"},
      {KnotType::kSurgeons, "surgeons"},
      {KnotType::kUnknown, "unknown"}};
  for (const auto& [type, word] : words) {
    EXPECT_EQ(KnotName(type), word);
    EXPECT_EQ(KnotTypeFromName(word), type);
  }
  EXPECT_FALSE(KnotTypeFromName("reef").has_value());
}

TEST(KnotRecognitionTest, ReferenceChiralityByBruteForceSigns) {
  // The shapes' handedness claims, checked independently of the recogniser.
  auto all_equal = [](const std::vector<int>& s, int v, std::size_t count) {
    return s.size() == count && std::all_of(s.begin(), s.end(), [v](int x) { return x == v; });
  };
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(shapes::TorusKnot(2, 3, 400), true), 1, 3));
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(shapes::TorusKnot(2, 3, 400, true), true), -1, 3));
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(shapes::OverhandAsTied(1, true), false), 1, 3));
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(shapes::OverhandAsTied(1, false), false), -1, 3));
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(shapes::OverhandAsTied(2, true), false), 1, 5));
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(shapes::OverhandAsTied(2, false), false), -1, 5));
  EXPECT_TRUE(all_equal(CrossingSignsAlongZ(Braid(2, {1, 1, 1}), true), 1, 3));
}

TEST(KnotRecognitionTest, ReferenceKnots) {
  for (const Case& c : ReferenceCases()) {
    SCOPED_TRACE(c.name);
    // Nine projection directions: every one must give the same invariants.
    const KnotAnalysis a = AnalyzeKnot(c.thread, {.num_projections = 9, .locate = false});
    EXPECT_EQ(a.projections_agreeing,
              a.type == KnotType::kNone && a.crossings == 0 && a.reduced_vertices <= 3 ? 1 : 9);
    EXPECT_EQ(KnotName(a.type), KnotName(c.expected))
        << c.thread.size() << " nodes, " << a.reduced_vertices << " reduced vertices, "
        << a.crossings << " crossings, signature " << a.signature << ", " << a.projections_agreeing
        << "/" << a.projections_tried << " projections agree";
    EXPECT_EQ(RecognizeKnot(c.thread), a.type);
  }
}

Eigen::Isometry3d RandomMotion(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  const Eigen::Quaterniond q = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = q.toRotationMatrix();
  x.translation() = Eigen::Vector3d(g(rng), g(rng), g(rng)) * 0.05;
  return x;
}

TEST(KnotRecognitionTest, InvariantToMotionScaleNoiseAndProjectionSeed) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> log_scale(-3.0, 3.0);
  int checked = 0;
  for (const Case& c : ReferenceCases()) {
    SCOPED_TRACE(c.name);
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::Isometry3d motion = RandomMotion(rng);
      const double scale = std::pow(10.0, log_scale(rng));
      Curve moved;
      for (const auto& p : c.thread) {
        // Noise of 1 % of the thread diameter on every coordinate.
        const Eigen::Vector3d noise(unit(rng), unit(rng), unit(rng));
        moved.push_back(scale * (motion * (p + 0.01 * kDiameter_m * noise)));
      }
      KnotOptions options;
      options.seed = rng();
      options.locate = false;
      EXPECT_EQ(KnotName(RecognizeKnot(moved, options)), KnotName(c.expected)) << "scale " << scale;
      ++checked;
    }
  }
  EXPECT_GT(checked, 60);
}

// A knot whose tails are cut short near the knot and end in a hook of two links pointing in
// a random direction (possibly straight at the knot).
Curve WithHookedEnds(const Curve& long_thread, std::mt19937_64& rng, int keep_tail_nodes) {
  // LongKnot threads: the knot body sits between the long tails; keep `keep_tail_nodes`
  // nodes of each tail beyond the body's bounding box.
  Eigen::AlignedBox3d body;
  for (std::size_t i = long_thread.size() / 4; i < 3 * long_thread.size() / 4; ++i) {
    body.extend(long_thread[i]);
  }
  std::size_t first = 0;
  while (!body.contains(long_thread[first])) ++first;
  std::size_t last = long_thread.size() - 1;
  while (!body.contains(long_thread[last])) --last;
  first = first >= static_cast<std::size_t>(keep_tail_nodes) ? first - keep_tail_nodes : 0;
  last = std::min(last + keep_tail_nodes, long_thread.size() - 1);
  Curve c(long_thread.begin() + static_cast<long>(first),
          long_thread.begin() + static_cast<long>(last) + 1);
  std::normal_distribution<double> g;
  auto hook = [&](Eigen::Vector3d end) {
    const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    return Curve{end + kDiameter_m * dir, end + 2.0 * kDiameter_m * dir};
  };
  const Curve head = hook(c.front());
  const Curve tail = hook(c.back());
  c.insert(c.begin(), head.rbegin(), head.rend());
  c.insert(c.end(), tail.begin(), tail.end());
  return c;
}

TEST(KnotRecognitionTest, EndsNearTheKnotPointingAnywhere) {
  std::mt19937_64 rng(99);
  const std::vector<std::pair<Curve, KnotType>> knots = {
      {LongThread(shapes::TorusKnot(2, 3, 400)), KnotType::kOverhandRight},
      {LongThread(shapes::FigureEightCurve(400)), KnotType::kFigureEight},
      {LongThread(shapes::TorusKnot(2, 5, 500)), KnotType::kDoubleOverhand},
  };
  for (const auto& [thread, expected] : knots) {
    for (int trial = 0; trial < 8; ++trial) {
      const Curve c = WithHookedEnds(thread, rng, 3 + trial);
      EXPECT_EQ(KnotName(RecognizeKnot(c)), KnotName(expected)) << "trial " << trial;
    }
  }
}

// Tails of random smooth walks, each in its own half-space (one rising above the knot, the
// other sinking below it), ending anywhere.
TEST(KnotRecognitionTest, WanderingTails) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  const Curve knot = shapes::ResampleClosed(shapes::TorusKnot(2, 3, 400), 0.1);
  // Open the knot at its highest and lowest... at two neighbouring nodes of largest z.
  int top = 0;
  for (int i = 0; i < static_cast<int>(knot.size()); ++i) {
    if (knot[i].z() > knot[top].z()) top = i;
  }
  for (int trial = 0; trial < 6; ++trial) {
    Curve body;
    const int n = static_cast<int>(knot.size());
    for (int k = 1; k < n; ++k) body.push_back(knot[(top + k) % n]);
    auto walk = [&](Eigen::Vector3d p, double rise) {
      Curve w;
      Eigen::Vector3d heading(g(rng), g(rng), 0.0);
      heading.normalize();
      for (int k = 0; k < 200; ++k) {
        heading += 0.4 * Eigen::Vector3d(g(rng), g(rng), 0.0);
        heading.z() = 0.0;
        heading.normalize();
        p += 0.1 * heading + Eigen::Vector3d(0, 0, rise);
        w.push_back(p);
      }
      return w;
    };
    // Rise straight out of the knot's slab first, then wander.
    Curve head = {body.front() + Eigen::Vector3d(0, 0, 0.6),
                  body.front() + Eigen::Vector3d(0, 0, 1.6)};
    const Curve head_walk = walk(head.back(), 0.01);
    head.insert(head.end(), head_walk.begin(), head_walk.end());
    Curve tail = {body.back() + Eigen::Vector3d(0, 0, 0.6)};
    // The other end leaves upwards too, then sinks below the knot well outside it.
    tail.push_back(tail.back() + Eigen::Vector3d(0, 0, 0.4));
    tail.push_back({6.0, 6.0, body.back().z() + 1.0});
    tail.push_back({6.0, 6.0, -3.0});
    const Curve tail_walk = walk(tail.back(), -0.01);
    tail.insert(tail.end(), tail_walk.begin(), tail_walk.end());
    // The upper tail wanders at z > 1.6 (above the knot), the lower one at z < -3.
    Curve thread(head.rbegin(), head.rend());
    thread.insert(thread.end(), body.begin(), body.end());
    thread.insert(thread.end(), tail.begin(), tail.end());
    EXPECT_EQ(KnotName(RecognizeKnot(ToThread(thread, 0.1))), "overhand-right") << trial;
  }
}

TEST(KnotRecognitionTest, LocatesTheKnottedCore) {
  // A trefoil in the middle of a long thread: the core lies within the knot's own arc.
  const Curve closed = shapes::ResampleClosed(shapes::TorusKnot(2, 3, 400), 0.1);
  const Curve long_knot = shapes::LongKnot(closed, 10.0);
  const Curve thread = ToThread(long_knot, 0.1);
  // Arc length of the knot body: from the tail's end (4 tail vertices before it) on.
  const double scale = kDiameter_m / 0.1;
  const double tail_before = shapes::Length(std::span(long_knot).first(5)) * scale;
  const double body = shapes::Length(closed) * scale;
  const KnotAnalysis a = AnalyzeKnot(thread);
  ASSERT_EQ(a.type, KnotType::kOverhandRight);
  ASSERT_TRUE(a.located);
  const double tol_m = 3.0 * kDiameter_m;
  EXPECT_GE(a.core_start_s_m, tail_before - tol_m);
  EXPECT_LE(a.core_end_s_m, tail_before + body + tol_m);
  EXPECT_GT(a.core_end_s_m - a.core_start_s_m, 0.3 * body);
  // The core's centre is inside the knot's bounding box.
  Eigen::AlignedBox3d box;
  for (const auto& p : closed) box.extend(p * scale);
  EXPECT_TRUE(box.contains(a.p_core_W)) << a.p_core_W.transpose();
  // No knot, nothing located.
  const KnotAnalysis none = AnalyzeKnot(ToThread(shapes::Coil(5, 1.0, 0.4, 40), 0.1));
  EXPECT_EQ(none.type, KnotType::kNone);
  EXPECT_FALSE(none.located);
}

TEST(KnotRecognitionTest, PlacementAroundAVessel) {
  // A knot carried around a vessel axis by known angles keeps its distance to the axis and
  // its angle advances by the same amount.
  const Curve base = LongThread(shapes::TorusKnot(2, 3, 400));
  const KnotAnalysis a0 = AnalyzeKnot(base);
  ASSERT_TRUE(a0.located);
  KnotTargetDef target;
  target.p_axis_W = a0.p_core_W + Eigen::Vector3d(0, 0, -1e-3);  // 1 mm below the knot
  target.axis_W = Eigen::Vector3d::UnitX();
  target.ref_W = Eigen::Vector3d::UnitZ();
  target.edge_W = {target.p_axis_W + Eigen::Vector3d(0, 0, 1e-3) + Eigen::Vector3d(5e-4, 0, 0)};
  const KnotPlacement p0 = CalcKnotPlacement(a0, target);
  EXPECT_NEAR(p0.angle_around_axis_rad, 0.0, 1e-9);
  EXPECT_NEAR(p0.radial_distance_m, 1e-3, 1e-12);
  EXPECT_NEAR(p0.distance_to_edge_m, 5e-4, 1e-12);
  EXPECT_NEAR(p0.core_center_s_m, 0.5 * (a0.core_start_s_m + a0.core_end_s_m), 1e-15);
  for (const double angle : {0.5, 2.0, -2.5}) {
    const Eigen::Isometry3d turn = Eigen::Translation3d(target.p_axis_W) *
                                   Eigen::AngleAxisd(angle, target.axis_W) *
                                   Eigen::Translation3d(-target.p_axis_W);
    Curve turned;
    for (const auto& p : base) turned.push_back(turn * p);
    const KnotAnalysis a = AnalyzeKnot(turned);
    ASSERT_TRUE(a.located);
    const KnotPlacement p = CalcKnotPlacement(a, target);
    EXPECT_NEAR(p.angle_around_axis_rad, angle, 1e-6);
    EXPECT_NEAR(p.radial_distance_m, p0.radial_distance_m, 1e-9);
    EXPECT_NEAR(p.core_center_s_m, p0.core_center_s_m, 1e-9);
  }
  KnotTargetDef bad = target;
  bad.ref_W = target.axis_W;
  EXPECT_THROW(CalcKnotPlacement(a0, bad), std::invalid_argument);
  bad = target;
  bad.edge_W.clear();
  EXPECT_THROW(CalcKnotPlacement(a0, bad), std::invalid_argument);
}

TEST(KnotRecognitionTest, RejectsBadInput) {
  const Curve one = {{0, 0, 0}};
  EXPECT_THROW(RecognizeKnot(one), std::invalid_argument);
  const Curve same = {{1, 1, 1}, {1, 1, 1}};
  EXPECT_THROW(RecognizeKnot(same), std::invalid_argument);
  const Curve nan = {{0, 0, 0}, {std::nan(""), 0, 0}};
  EXPECT_THROW(RecognizeKnot(nan), std::invalid_argument);
  const Curve ok = {{0, 0, 0}, {1e-3, 0, 0}};
  EXPECT_EQ(RecognizeKnot(ok), KnotType::kNone);
  EXPECT_THROW(RecognizeKnot(ok, {.num_projections = 0}), std::invalid_argument);
  EXPECT_THROW(RecognizeKnot(ok, {.thread_diameter_m = -1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace microdex::knot
