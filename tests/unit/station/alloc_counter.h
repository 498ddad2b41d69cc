#pragma once
// Counts heap allocations made on the calling thread while enabled: the global operator new
// of the test binary is replaced (alloc_counter.cc).

#include <cstdint>

namespace microdex::testing {

void StartCountingAllocations();
// Stops counting and returns the number of allocations since Start.
std::uint64_t StopCountingAllocations();

}  // namespace microdex::testing
