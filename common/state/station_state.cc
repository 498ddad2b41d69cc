#include "common/state/station_state.h"

#include <cstring>
#include <type_traits>
#include <vector>

#include "common/state/station_state_visit.h"

namespace microdex::state {
namespace {

// Every field's bytes in visit order, bools as 0/1.
class Serializer {
 public:
  template <typename T>
  void operator()(const char* /*name*/, const T* p, std::size_t n) {
    if constexpr (std::is_same_v<T, bool>) {
      for (std::size_t i = 0; i < n; ++i) bytes.push_back(p[i] ? 1 : 0);
    } else {
      const auto* b = reinterpret_cast<const unsigned char*>(p);
      bytes.insert(bytes.end(), b, b + n * sizeof(T));
    }
  }
  std::vector<unsigned char> bytes;
};

}  // namespace

void SeedStationState(std::uint64_t seed, StationState& state) {
  state.seed = seed;
  state.rng = seed;
}

std::uint64_t NextRandom(StationState& state) {
  // SplitMix64 (Steele, Lea, Flood 2014).
  std::uint64_t z = (state.rng += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

bool operator==(const StationState& a, const StationState& b) {
  Serializer sa, sb;
  VisitStationState(a, sa);
  VisitStationState(b, sb);
  return sa.bytes == sb.bytes;
}

}  // namespace microdex::state
