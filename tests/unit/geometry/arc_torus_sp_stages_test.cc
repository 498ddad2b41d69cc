// The SP clearance stage by stage (arc_torus_sp_*.h), each against something independent of
// it: the clip against the azimuth of densely sampled needle points, the lift against the
// sign of r − distance, the solve against a dense scan of φ, the ascent against a dense scan
// of the distance, the certificate against a brute-force farther point, the fall-backs
// against their definitions; and the whole query with and without diagnostics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/arc_torus_sp_ascent.h"
#include "common/geometry/arc_torus_sp_certify.h"
#include "common/geometry/arc_torus_sp_clip.h"
#include "common/geometry/arc_torus_sp_fallback.h"
#include "common/geometry/arc_torus_sp_lift.h"
#include "common/geometry/arc_torus_sp_solve.h"
#include "common/geometry/stereographic.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry::sp {
namespace {

using testing::MakeNearCoreArcTorus;
using testing::MakeWideArcTorus;
using testing::RandomArcTorus;

// Distance² from the needle point at s to the core circle, in long double.
long double DistSq(const NeedleInV& nv, double core_r, long double s) {
  const long double x = nv.o.x() + nv.rho * (std::cos(s) * nv.e1.x() + std::sin(s) * nv.e2.x());
  const long double y = nv.o.y() + nv.rho * (std::cos(s) * nv.e1.y() + std::sin(s) * nv.e2.y());
  const long double z = nv.o.z() + nv.rho * (std::cos(s) * nv.e1.z() + std::sin(s) * nv.e2.z());
  const long double e = std::sqrt(x * x + y * y) - core_r;
  return e * e + z * z;
}

struct Clipped {
  NeedleInV nv;
  Interval iv[kMaxIntervals];
  int n = 0;
};

Clipped Clip(const RandomArcTorus& c) {
  Clipped k;
  k.nv = MakeNeedleInV(c.arc, c.torus);
  k.n = ClipArcToSegment(k.nv, c.arc.sweep_rad, std::cos(c.arc.sweep_rad),
                         std::sin(c.arc.sweep_rad), c.torus.segment_angle_rad, k.iv);
  return k;
}

// The largest distance² on the clipped arc: a dense scan, each sampled local maximum refined
// by golden section.
long double BruteMaxDistSq(const Clipped& k, double core_r) {
  long double best = -1;
  for (int i = 0; i < k.n; ++i) {
    const int samples = 4000;
    const long double lo = k.iv[i].lo, hi = k.iv[i].hi, h = (hi - lo) / samples;
    std::vector<long double> f(samples + 1);
    for (int j = 0; j <= samples; ++j) f[j] = DistSq(k.nv, core_r, lo + j * h);
    for (int j = 0; j <= samples; ++j) {
      best = std::max(best, f[j]);
      if ((j > 0 && f[j] < f[j - 1]) || (j < samples && f[j] < f[j + 1])) continue;
      long double a = std::max(lo, lo + (j - 1) * h), b = std::min(hi, lo + (j + 1) * h);
      for (int it = 0; it < 80; ++it) {
        const long double m1 = b - 0.6180339887498949L * (b - a);
        const long double m2 = a + 0.6180339887498949L * (b - a);
        if (DistSq(k.nv, core_r, m1) < DistSq(k.nv, core_r, m2)) {
          a = m1;
        } else {
          b = m2;
        }
      }
      best = std::max(best, DistSq(k.nv, core_r, 0.5L * (a + b)));
    }
  }
  return best;
}

TEST(SpClip, PiecesHoldExactlyTheNeedlePointsInsideTheSegment) {
  std::mt19937_64 rng(11);
  int with_segment = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const RandomArcTorus c = MakeWideArcTorus(rng);
    const Clipped k = Clip(c);
    ASSERT_LE(k.n, kMaxIntervals);
    with_segment += c.torus.segment_angle_rad < 2 * kPi;
    for (int i = 0; i < k.n; ++i) {
      EXPECT_LE(k.iv[i].lo, k.iv[i].hi);
      if (i > 0) {
        EXPECT_LT(k.iv[i - 1].hi, k.iv[i].lo) << "pieces are ordered and apart";
      }
      EXPECT_NEAR(k.iv[i].cos_lo, std::cos(k.iv[i].lo), 1e-12);
      EXPECT_NEAR(k.iv[i].sin_lo, std::sin(k.iv[i].lo), 1e-12);
      EXPECT_NEAR(k.iv[i].cos_hi, std::cos(k.iv[i].hi), 1e-12);
      EXPECT_NEAR(k.iv[i].sin_hi, std::sin(k.iv[i].hi), 1e-12);
    }
    // Every sample away from a piece end is inside a piece exactly when its azimuth is in
    // the segment.
    const int samples = 2000;
    for (int j = 0; j <= samples; ++j) {
      const double s = c.arc.sweep_rad * j / samples;
      bool near_end = false, in_piece = false;
      for (int i = 0; i < k.n; ++i) {
        near_end = near_end || std::abs(s - k.iv[i].lo) < 1e-7 || std::abs(s - k.iv[i].hi) < 1e-7;
        in_piece = in_piece || (s >= k.iv[i].lo && s <= k.iv[i].hi);
      }
      if (near_end) continue;
      const Eigen::Vector3d p = k.nv.PointAt(s);
      ASSERT_EQ(in_piece, IsAzimuthInSegment(p.x(), p.y(), c.torus.segment_angle_rad))
          << "trial " << trial << " s " << s;
    }
  }
  EXPECT_GT(with_segment, 100);
}

TEST(SpClip, WholeTorusIsOnePieceAndFindIntervalSnaps) {
  std::mt19937_64 rng(12);
  RandomArcTorus c = MakeNearCoreArcTorus(rng);
  c.torus.segment_angle_rad = 2 * kPi;
  const Clipped k = Clip(c);
  ASSERT_EQ(k.n, 1);
  EXPECT_EQ(k.iv[0].lo, 0);
  EXPECT_EQ(k.iv[0].hi, c.arc.sweep_rad);
  EXPECT_EQ(FindInterval(k.iv, k.n, 0.5 * c.arc.sweep_rad), 0);
  EXPECT_EQ(FindInterval(k.iv, k.n, c.arc.sweep_rad + 1e-13), 0) << "rounding past the end";
  EXPECT_EQ(FindInterval(k.iv, k.n, c.arc.sweep_rad + 1e-6), -1);
}

TEST(SpLift, ConicHasTheSignOfTubeRadiusMinusDistance) {
  // sign(G) = sign(t − distance to the core circle) (thesis §4.2): the lifted conic at the
  // lift of each needle point, for level tori of several tube radii t < R.
  std::mt19937_64 rng(21);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const RandomArcTorus c = MakeNearCoreArcTorus(rng);
    const NeedleInV nv = MakeNeedleInV(c.arc, c.torus);
    const double R = c.torus.core_radius_m;
    for (const double t : {0.05 * R, c.torus.tube_radius_m, 0.7 * R}) {
      LiftedConic k;
      LiftLevelTorus(nv, t, (R - t) * (R + t), &k);
      ASSERT_TRUE(k.ok);
      for (int j = 0; j < 50; ++j) {
        const double s = c.arc.sweep_rad * j / 49;
        const long double d = std::sqrt(DistSq(nv, R, s));
        if (std::abs(static_cast<double>(d) - t) < 1e-9 * R) continue;
        // The lifted point on the circle: X = c + cos θ a_x + sin θ a_y with θ found from X.
        const Eigen::Vector4d X = LiftToS3(k.lambda * nv.PointAt(s));
        const Eigen::Vector4d rel = X - k.lc.center;
        const double ct = rel.dot(k.lc.ax) / k.lc.radius_sq;
        const double st = rel.dot(k.lc.ay) / k.lc.radius_sq;
        EXPECT_NEAR(ct * ct + st * st, 1.0, 1e-8) << "the lift of the needle is the circle";
        const double phi = k.conic.Eval(ct, st);
        EXPECT_EQ(phi > 0, d < t) << "trial " << trial << " t " << t << " s " << s;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 20000);
}

TEST(SpSolve, MinimaOfPhiAreTheDenseScansMinima) {
  // Every local minimum of φ along the clipped arc found by a dense scan (interior, away from
  // the piece ends) is matched by one of the pass's minima.
  std::mt19937_64 rng(31);
  int matched = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const RandomArcTorus c = MakeNearCoreArcTorus(rng);
    const Clipped k = Clip(c);
    if (k.n == 0) continue;
    const double R = c.torus.core_radius_m, r = c.torus.tube_radius_m;
    SpPass pass;
    RunSpPass(k.nv, R, r, k.iv, k.n, SpOptions{}, false, std::numeric_limits<double>::infinity(),
              &pass);
    if (!pass.ok) continue;
    const TorusLiftScale scale = CalcTorusLiftScale(R, r);
    const auto phi_at = [&](double s) {
      const Eigen::Vector4d X = LiftToS3(scale.lambda * k.nv.PointAt(s));
      return EvalLiftedTorus(scale.alpha, X);
    };
    for (int i = 0; i < k.n; ++i) {
      const int samples = 3000;
      const double h = (k.iv[i].hi - k.iv[i].lo) / samples;
      for (int j = 2; j < samples - 1; ++j) {
        const double s = k.iv[i].lo + j * h;
        const double f0 = phi_at(s - h), f1 = phi_at(s), f2 = phi_at(s + h);
        if (!(f1 < f0 && f1 < f2)) continue;
        double nearest = std::numeric_limits<double>::infinity();
        for (int m = 0; m < pass.n; ++m) {
          if (pass.is_min[m]) nearest = std::min(nearest, std::abs(pass.s[m] - s));
        }
        EXPECT_LT(nearest, 2 * h) << "trial " << trial << " minimum of φ at s = " << s;
        ++matched;
      }
    }
  }
  EXPECT_GT(matched, 50);
}

TEST(SpAscent, AdvanceAngleIsTheRotation) {
  for (double s = -3; s <= 3; s += 0.37) {
    for (const double h : {-0.5, -0.1, -1e-6, 0.0, 1e-9, 0.2, 0.5, 0.9}) {
      double cs = std::cos(s), sn = std::sin(s);
      AdvanceAngle(s + h, h, &cs, &sn);
      EXPECT_NEAR(cs, std::cos(s + h), 4e-16) << s << " " << h;
      EXPECT_NEAR(sn, std::sin(s + h), 4e-16) << s << " " << h;
    }
  }
}

TEST(SpAscent, ClimbsToTheLocalMaximumOfTheDistance) {
  std::mt19937_64 rng(41);
  int climbs = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const RandomArcTorus c = MakeNearCoreArcTorus(rng);
    const Clipped k = Clip(c);
    const double R = c.torus.core_radius_m;
    for (int i = 0; i < k.n; ++i) {
      const double s0 = k.iv[i].lo + 0.37 * (k.iv[i].hi - k.iv[i].lo);
      const Candidate start =
          MakeCandidate(k.nv, R, s0, std::cos(s0), std::sin(s0), i, CandidateKind::kInterior);
      Best best;
      const double f = TryCandidate(k.nv, R, k.iv, start, SpOptions{}, &best);
      EXPECT_GE(f, start.f) << "the ascent never descends";
      EXPECT_GE(best.s, k.iv[i].lo);
      EXPECT_LE(best.s, k.iv[i].hi);
      EXPECT_NEAR(best.f, static_cast<double>(DistSq(k.nv, R, best.s)), 1e-12 * R * R);
      // A local maximum (or a piece end): no better point within a small step inside the piece.
      for (const double ds : {-1e-4, 1e-4}) {
        const double s = std::clamp(best.s + ds, k.iv[i].lo, k.iv[i].hi);
        EXPECT_LE(static_cast<double>(DistSq(k.nv, R, s)), best.f * (1 + 1e-12) + 1e-30)
            << "trial " << trial;
      }
      ++climbs;
    }
  }
  EXPECT_GT(climbs, 200);
}

TEST(SpCertify, NeverProvesWhileAFartherPointExists) {
  // From a starting point that is not the deepest one, the certificate rounds (quick test,
  // lifted pass) must keep finding farther points until the brute-force maximum is reached:
  // "proved" with a point farther than the best by more than the tolerance would be unsound.
  std::mt19937_64 rng(51);
  int proofs = 0, improvements = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const RandomArcTorus c = trial % 2 ? MakeNearCoreArcTorus(rng) : MakeWideArcTorus(rng);
    const Clipped k = Clip(c);
    if (k.n == 0) continue;
    const double R = c.torus.core_radius_m;
    const long double truth = BruteMaxDistSq(k, R);
    if (IsDeep(static_cast<double>(truth), R)) continue;  // beyond the horn torus: exact's job
    // The certificate's precondition, as the query establishes it: no piece end is farther
    // than the best point (the farthest end, ascended). That is all: the ascent may stop at a
    // local maximum that is not the deepest.
    Candidate ends[2 * kMaxIntervals];
    int n_ends = 0;
    AddPieceEnds(k.nv, R, k.iv, k.n, ends, &n_ends);
    const Candidate* farthest = std::max_element(
        ends, ends + n_ends, [](const Candidate& a, const Candidate& b) { return a.f < b.f; });
    Best best;
    TryCandidate(k.nv, R, k.iv, *farthest, SpOptions{}, &best);
    for (int round = 0; round < 8 && !IsDeep(best.f, R); ++round) {
      CertifyStep step = QuickCertify(k.nv, R, k.iv, k.n, SpOptions{}, &best);
      if (step == CertifyStep::kNeedsLiftedPass) {
        bool uniform = false;
        step = LiftedCertify(k.nv, R, k.iv, k.n, SpOptions{}, &best, &uniform);
      }
      if (step == CertifyStep::kImproved) {
        ++improvements;
        continue;
      }
      ASSERT_NE(step, CertifyStep::kNeedsLiftedPass);
      // Proved: the brute force finds nothing farther beyond the certificate's tolerance.
      const double d_best = std::sqrt(best.f), d_true = std::sqrt(static_cast<double>(truth));
      EXPECT_LE(d_true - d_best, 1e-10 * std::max(R, d_true)) << "trial " << trial;
      ++proofs;
      break;
    }
  }
  EXPECT_GT(proofs, 120);
  EXPECT_GT(improvements, 5) << "some ascents stop short of the deepest point";
}

TEST(SpCertify, ProvesAtTheDeepestPoint) {
  std::mt19937_64 rng(52);
  int proved = 0, tried = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const RandomArcTorus c = MakeNearCoreArcTorus(rng);
    const ArcTorusClearance exact = CalcArcTorusClearanceExact(c.arc, c.torus);
    if (exact.status != ClearanceStatus::kOk) continue;
    const Clipped k = Clip(c);
    const double R = c.torus.core_radius_m;
    const double d = c.torus.tube_radius_m - exact.clearance_m;
    const double s = exact.s_rad;
    Best best{d * d, s, std::cos(s), std::sin(s)};
    ++tried;
    proved += QuickCertify(k.nv, R, k.iv, k.n, SpOptions{}, &best) == CertifyStep::kProved;
  }
  EXPECT_GT(tried, 150);
  EXPECT_GE(proved, tried * 9 / 10) << "the quick test settles the deepest point itself";
}

TEST(SpFallback, UniformStartsAreInsideEveryPiece) {
  std::mt19937_64 rng(61);
  for (int trial = 0; trial < 100; ++trial) {
    const RandomArcTorus c = MakeWideArcTorus(rng);
    const Clipped k = Clip(c);
    Candidate cand[kMaxCandidates];
    int n = 0;
    AddUniformCandidates(k.nv, c.torus.core_radius_m, k.iv, k.n, cand, &n);
    ASSERT_EQ(n, k.n * kRobustSamples);
    for (int j = 0; j < n; ++j) {
      const Interval& iv = k.iv[cand[j].interval];
      EXPECT_GT(cand[j].s, iv.lo);
      EXPECT_LT(cand[j].s, iv.hi);
      const double f = static_cast<double>(DistSq(k.nv, c.torus.core_radius_m, cand[j].s));
      EXPECT_NEAR(cand[j].f, f, 1e-12 * std::max(f, c.torus.core_radius_m * c.torus.core_radius_m));
    }
  }
}

TEST(SpFallback, ExactFallbackIsTheExactMethodAndIsRecorded) {
  std::mt19937_64 rng(62);
  const RandomArcTorus c = MakeWideArcTorus(rng);
  SpDiagnostics diag;
  const ArcTorusClearance a = FallBackToExact(c.arc, c.torus, &diag);
  const ArcTorusClearance b = CalcArcTorusClearanceExact(c.arc, c.torus);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.clearance_m, b.clearance_m);
  EXPECT_TRUE(diag.deep_fallback());
  EXPECT_EQ(diag.decision, SpDecision::kExact);
}

TEST(SpQuery, DiagnosticsDoNotChangeTheAnswerAndNameTheDecidingStage) {
  std::mt19937_64 rng(71);
  int counts[8] = {};
  for (int trial = 0; trial < 3000; ++trial) {
    const RandomArcTorus c = trial % 2 ? MakeNearCoreArcTorus(rng) : MakeWideArcTorus(rng);
    SpDiagnostics diag;
    const ArcTorusClearance with = CalcArcTorusClearanceSP(c.arc, c.torus, {}, &diag);
    const ArcTorusClearance without = CalcArcTorusClearanceSP(c.arc, c.torus);
    ASSERT_EQ(with.status, without.status);
    if (with.status == ClearanceStatus::kOk) {
      EXPECT_EQ(with.clearance_m, without.clearance_m) << "trial " << trial;
      EXPECT_EQ(with.s_rad, without.s_rad) << "trial " << trial;
    }
    ++counts[static_cast<int>(diag.decision)];
    if (with.status == ClearanceStatus::kEmptyRange) {
      EXPECT_EQ(diag.decision, SpDecision::kEmptyRange);
    }
    if (diag.decision == SpDecision::kExact) {
      EXPECT_TRUE(diag.deep_fallback());
    }
  }
  EXPECT_EQ(counts[static_cast<int>(SpDecision::kThesisPass)], 0) << "the default certifies";
  EXPECT_GT(counts[static_cast<int>(SpDecision::kQuickCertificate)], 2000);
  EXPECT_GT(counts[static_cast<int>(SpDecision::kEmptyRange)], 0);
  // Without the certificate the thesis's pass decides every query with a range.
  SpOptions thesis;
  thesis.polish_max_iters = 0;
  SpDiagnostics diag;
  const RandomArcTorus c = MakeNearCoreArcTorus(rng);
  CalcArcTorusClearanceSP(c.arc, c.torus, thesis, &diag);
  EXPECT_TRUE(diag.decision == SpDecision::kThesisPass || diag.decision == SpDecision::kEmptyRange);
}

}  // namespace
}  // namespace microdex::geometry::sp
