#pragma once
// Counts heap allocations made on the calling thread while enabled. The test binary replaces
// the global operator new and, outside sanitizer builds (which own malloc), also malloc and
// its relatives, so allocations inside C libraries (CHOLMOD's workspace, ...) are counted too
// (alloc_counter.cc).

#include <cstdint>

namespace microdex::testing {

void StartCountingAllocations();
// Stops counting and returns the number of allocations since Start.
std::uint64_t StopCountingAllocations();
// True when malloc itself is counted (not under ASan/TSan).
bool CountsMalloc();

}  // namespace microdex::testing
