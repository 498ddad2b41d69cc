// The per-query methods used on the haptic path (exact, sampled) never allocate.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/arc_torus_sampled.h"
#include "tests/support/alloc_counter.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace microdex::geometry {
namespace {

TEST(ArcTorusAllocation, ExactAndSampledQueriesDoNotAllocate) {
  std::mt19937_64 rng(21);
  std::vector<testing::RandomArcTorus> cases;
  for (int i = 0; i < 2000; ++i) {
    cases.push_back(i % 2 ? testing::MakeWideArcTorus(rng) : testing::MakeNearCoreArcTorus(rng));
  }
  cases.back().torus.tube_radius_m = -1;  // invalid input too
  volatile double sink = 0;
  ::microdex::testing::StartCountingAllocations();
  for (const auto& c : cases) {
    sink = sink + CalcArcTorusClearanceExact(c.arc, c.torus).clearance_m;
    sink = sink + CalcArcTorusClearanceSampled(c.arc, c.torus, 50).clearance_m;
    sink = sink + CalcArcTorusClearanceSampledClipped(c.arc, c.torus, 50).clearance_m;
    sink = sink + (FindArcTorusInputError(c.arc, c.torus) == nullptr);
  }
  EXPECT_EQ(::microdex::testing::StopCountingAllocations(), 0u);
}

}  // namespace
}  // namespace microdex::geometry
