// The per-query methods used on the haptic path (exact, sampled) never allocate.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "common/geometry/arc_torus_exact.h"
#include "common/geometry/arc_torus_sampled.h"
#include "tests/unit/geometry/random_arc_torus.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

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
  const long before = g_allocations.load();
  for (const auto& c : cases) {
    sink = sink + CalcArcTorusClearanceExact(c.arc, c.torus).clearance_m;
    sink = sink + CalcArcTorusClearanceSampled(c.arc, c.torus, 50).clearance_m;
    sink = sink + CalcArcTorusClearanceSampledClipped(c.arc, c.torus, 50).clearance_m;
    sink = sink + (FindArcTorusInputError(c.arc, c.torus) == nullptr);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
}

}  // namespace
}  // namespace microdex::geometry
