// Knot diagrams and invariants (common/knot/diagram, invariants, projection)
// against knot-table values and against their own invariance: every projection of a curve,
// both checkerboard colourings, before and after Reidemeister simplification, must give the
// same Alexander polynomial, determinant, signature and Jones polynomial.
#include "common/knot/invariants.h"

#include <gtest/gtest.h>

#include <random>

#include "common/knot/closure.h"
#include "common/knot/diagram.h"
#include "common/knot/projection.h"
#include "tests/support/knot_shapes.h"

namespace microdex::knot {
// Readable polynomials in failure messages.
void PrintTo(const LaurentPolynomial& p, std::ostream* os) { *os << ToString(p); }

namespace {

using shapes::Curve;

Eigen::Vector3d RandomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
}

// Gauss code of `closed` along a random generic direction.
GaussCode Project(const Curve& closed, std::mt19937_64& rng) {
  for (int attempt = 0; attempt < 20; ++attempt) {
    if (auto code = ProjectPolygon(closed, RandomUnit(rng))) return *code;
  }
  ADD_FAILURE() << "no generic projection found";
  return {};
}

struct Invariants {
  LaurentPolynomial alexander;
  int signature = 0;
  std::int64_t determinant = 0;
};

Invariants Compute(const GaussCode& code) {
  const PlanarDiagram pd = MakePlanarDiagram(code);
  const GoeritzResult g0 = GoeritzSignature(pd, 0);
  const GoeritzResult g1 = GoeritzSignature(pd, 1);
  // Gordon-Litherland: either colouring gives the knot's signature.
  EXPECT_EQ(g0.signature, g1.signature);
  EXPECT_EQ(g0.determinant, g1.determinant);
  return {AlexanderPolynomial(pd), g0.signature, g0.determinant};
}

// Literature values (Rolfsen table / Jones 1985; right-handed = positive crossings).
const LaurentPolynomial kAlex31{-1, {1, -1, 1}};
const LaurentPolynomial kAlex41{-1, {1, -3, 1}};
const LaurentPolynomial kAlex51{-2, {1, -1, 1, -1, 1}};
const LaurentPolynomial kAlex52{-1, {2, -3, 2}};
const LaurentPolynomial kJonesRightTrefoil{1, {1, 0, 1, -1}};  // t + t^3 - t^4
const LaurentPolynomial kJonesFigureEight{-2, {1, -1, 1, -1, 1}};
const LaurentPolynomial kJonesPositive51{2, {1, 0, 1, -1, 1, -1}};  // t^2+t^4-t^5+t^6-t^7
const LaurentPolynomial kJonesPositive52{1, {1, -1, 2, -1, 1, -1}};

struct TableCase {
  const char* name;
  Curve closed;
  LaurentPolynomial alexander;
  int signature;
  LaurentPolynomial jones;
};

std::vector<TableCase> TableCases() {
  const int w31[] = {1, 1, 1};
  const int w31m[] = {-1, -1, -1};
  const int w41[] = {1, -2, 1, -2};
  const int w51[] = {1, 1, 1, 1, 1};
  const int w52[] = {1, 1, 1, 2, -1, 2};
  const int w52m[] = {-1, -1, -1, -2, 1, -2};
  return {
      {"braid right trefoil", shapes::BraidClosure(2, w31), kAlex31, -2, kJonesRightTrefoil},
      {"braid left trefoil", shapes::BraidClosure(2, w31m), kAlex31, 2, Mirror(kJonesRightTrefoil)},
      {"torus T(2,3)", shapes::TorusKnot(2, 3, 300), kAlex31, -2, kJonesRightTrefoil},
      {"mirrored torus T(2,3)", shapes::TorusKnot(2, 3, 300, true), kAlex31, 2,
       Mirror(kJonesRightTrefoil)},
      {"braid figure-eight", shapes::BraidClosure(3, w41), kAlex41, 0, kJonesFigureEight},
      {"Lissajous figure-eight", shapes::FigureEightCurve(400), kAlex41, 0, kJonesFigureEight},
      {"braid 5_1", shapes::BraidClosure(2, w51), kAlex51, -4, kJonesPositive51},
      {"torus T(2,5)", shapes::TorusKnot(2, 5, 500), kAlex51, -4, kJonesPositive51},
      {"braid 5_2", shapes::BraidClosure(3, w52), kAlex52, -2, kJonesPositive52},
      {"mirrored braid 5_2", shapes::BraidClosure(3, w52m), kAlex52, 2, Mirror(kJonesPositive52)},
  };
}

TEST(KnotInvariantsTest, TableKnotsInEveryProjection) {
  std::mt19937_64 rng(7);
  for (const TableCase& c : TableCases()) {
    SCOPED_TRACE(c.name);
    for (int k = 0; k < 6; ++k) {
      const GaussCode raw = Project(c.closed, rng);
      const GaussCode simple = SimplifyReidemeister(raw);
      EXPECT_LE(simple.num_crossings(), raw.num_crossings());
      const Invariants before = Compute(raw);
      const Invariants after = Compute(simple);
      EXPECT_EQ(before.alexander, c.alexander) << ToString(before.alexander);
      EXPECT_EQ(after.alexander, c.alexander) << ToString(after.alexander);
      EXPECT_EQ(before.signature, c.signature);
      EXPECT_EQ(after.signature, c.signature);
      // det = |Delta(-1)| = |det Goeritz|.
      EXPECT_EQ(std::llabs(EvaluateAtPlusMinusOne(c.alexander, -1)), before.determinant);
      if (simple.num_crossings() <= 14) {
        const LaurentPolynomial jones = JonesPolynomial(MakePlanarDiagram(simple));
        EXPECT_EQ(jones, c.jones) << ToString(jones);
        // V(1) = 1 and |V(-1)| = det for every knot.
        EXPECT_EQ(EvaluateAtPlusMinusOne(jones, 1), 1);
        EXPECT_EQ(std::llabs(EvaluateAtPlusMinusOne(jones, -1)), before.determinant);
      }
    }
  }
}

TEST(KnotInvariantsTest, ConnectedSumsMultiplyAndAdd) {
  // Braid closures of products on strands sharing one strand are connected sums.
  const int granny[] = {1, 1, 1, 2, 2, 2};
  const int square[] = {1, 1, 1, -2, -2, -2};
  const int surgeons[] = {1, 1, 1, 2, -1, 2, -3, -3, -3};
  std::mt19937_64 rng(11);
  struct SumCase {
    Curve closed;
    LaurentPolynomial alexander;
    int signature;
    LaurentPolynomial jones;
  };
  const std::vector<SumCase> cases = {
      {shapes::BraidClosure(3, granny), Multiply(kAlex31, kAlex31), -4,
       Multiply(kJonesRightTrefoil, kJonesRightTrefoil)},
      {shapes::BraidClosure(3, square), Multiply(kAlex31, kAlex31), 0,
       Multiply(kJonesRightTrefoil, Mirror(kJonesRightTrefoil))},
      {shapes::BraidClosure(4, surgeons), Multiply(kAlex52, kAlex31), 0,
       Multiply(kJonesPositive52, Mirror(kJonesRightTrefoil))},
  };
  for (const SumCase& c : cases) {
    for (int k = 0; k < 4; ++k) {
      const GaussCode simple = SimplifyReidemeister(Project(c.closed, rng));
      const Invariants inv = Compute(simple);
      EXPECT_EQ(inv.alexander, c.alexander) << ToString(inv.alexander);
      EXPECT_EQ(inv.signature, c.signature);
    }
    // The Jones polynomial on the braid's own view (few crossings).
    const auto top = ProjectPolygon(c.closed, Eigen::Vector3d(0.01, 0.02, 1.0).normalized());
    ASSERT_TRUE(top.has_value());
    const GaussCode simple = SimplifyReidemeister(*top);
    ASSERT_LE(simple.num_crossings(), 16);
    EXPECT_EQ(JonesPolynomial(MakePlanarDiagram(simple)), c.jones);
  }
}

TEST(KnotInvariantsTest, HandWrittenTrefoilGaussCode) {
  // O1 U2 O3 U1 O2 U3: the standard trefoil diagram; all positive = right-handed.
  GaussCode code;
  code.passages = {{0, true}, {1, false}, {2, true}, {0, false}, {1, true}, {2, false}};
  code.sign = {1, 1, 1};
  const PlanarDiagram pd = MakePlanarDiagram(code);
  EXPECT_EQ(pd.num_faces, 5);
  EXPECT_EQ(AlexanderPolynomial(pd), kAlex31);
  EXPECT_EQ(GoeritzSignature(pd).signature, -2);
  EXPECT_EQ(JonesPolynomial(pd), kJonesRightTrefoil);
  code.sign = {-1, -1, -1};
  for (auto& p : code.passages) p.over = !p.over;  // the mirror image
  const PlanarDiagram mirror = MakePlanarDiagram(code);
  EXPECT_EQ(GoeritzSignature(mirror).signature, 2);
  EXPECT_EQ(JonesPolynomial(mirror), Mirror(kJonesRightTrefoil));
}

TEST(KnotInvariantsTest, ReidemeisterMovesUndoCoilAndTwists) {
  // A side view of a coil closed outside: every crossing goes by Reidemeister I/II.
  const Curve coil = shapes::Coil(12, 1.0, 0.5, 32);
  const Curve closed = CloseThread(coil, 0.1);
  for (const Eigen::Vector3d& dir :
       {Eigen::Vector3d(1, 0.05, 0.02), Eigen::Vector3d(0.3, 1, 0.1)}) {
    const auto raw = ProjectPolygon(closed, dir.normalized());
    ASSERT_TRUE(raw.has_value());
    EXPECT_GE(raw->num_crossings(), 10);
    EXPECT_EQ(SimplifyReidemeister(*raw).num_crossings(), 0);
  }
  // A kink added by hand to the trefoil code goes too.
  GaussCode code;
  code.passages = {{0, true}, {3, true},  {3, false}, {1, false},
                   {2, true}, {0, false}, {1, true},  {2, false}};
  code.sign = {1, 1, 1, -1};
  const GaussCode simple = SimplifyReidemeister(code);
  EXPECT_EQ(simple.num_crossings(), 3);
  EXPECT_EQ(Writhe(simple), 3);
}

TEST(KnotInvariantsTest, MessyUnknotDiagramsHaveTrivialInvariants) {
  // Ascending random walks are unknots however many crossings their projections keep.
  std::mt19937_64 rng(3);
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const Curve walk = shapes::AscendingRandomWalk(150, 1.0, 0.05, seed);
    const Curve closed = CloseThread(walk, 1.0);
    const GaussCode raw = Project(closed, rng);
    EXPECT_GE(raw.num_crossings(), 10);
    const Invariants inv = Compute(SimplifyReidemeister(raw));
    EXPECT_EQ(inv.alexander, (LaurentPolynomial{0, {1}}));
    EXPECT_EQ(inv.signature, 0);
    EXPECT_EQ(inv.determinant, 1);
  }
}

TEST(KnotInvariantsTest, PolynomialHelpers) {
  const LaurentPolynomial p{-1, {1, -1, 1}};
  EXPECT_EQ(ToString(p), "t^-1 - 1 + t");
  EXPECT_EQ(Multiply(p, p), (LaurentPolynomial{-2, {1, -2, 3, -2, 1}}));
  EXPECT_EQ(Mirror(kJonesRightTrefoil), (LaurentPolynomial{-4, {-1, 1, 0, 1}}));
  EXPECT_EQ(Add(p, LaurentPolynomial{-1, {-1, 1, -1}}), (LaurentPolynomial{0, {}}));
  EXPECT_EQ(EvaluateAtPlusMinusOne(kAlex41, -1), -5);  // 1 - 3 t + t^2 at t = -1, over t
  EXPECT_EQ(EvaluateAtPlusMinusOne(kAlex41, 1), -1);
}

}  // namespace
}  // namespace microdex::knot
