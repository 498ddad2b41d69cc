#include "common/state/state_hash.h"

#define XXH_STATIC_LINKING_ONLY  // XXH3_state_t on the stack: no allocation
#include <xxhash.h>

#include <bit>
#include <cstring>
#include <type_traits>

#include "common/base/check.h"
#include "common/state/station_state_visit.h"

namespace microdex::state {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the state hash is defined on little-endian bytes");

// Small fields are gathered in a buffer and handed to XXH3 in blocks; long arrays go straight.
class HashVisitor {
 public:
  HashVisitor() { MICRODEX_CHECK(XXH3_64bits_reset(&xxh_) == XXH_OK); }

  template <typename T>
  void operator()(const char* /*name*/, const T* p, std::size_t n) {
    if constexpr (std::is_same_v<T, bool>) {
      for (std::size_t i = 0; i < n; ++i) Put(static_cast<std::uint8_t>(p[i] ? 1 : 0));
    } else {
      static_assert(std::is_arithmetic_v<T>);
      const std::size_t bytes = n * sizeof(T);
      if (bytes >= kDirectBytes) {
        Flush();
        XXH3_64bits_update(&xxh_, p, bytes);
      } else {
        if (used_ + bytes > sizeof buffer_) Flush();
        std::memcpy(buffer_ + used_, p, bytes);
        used_ += bytes;
      }
    }
  }

  std::uint64_t Digest() {
    Flush();
    return XXH3_64bits_digest(&xxh_);
  }

 private:
  static constexpr std::size_t kDirectBytes = 256;

  void Put(std::uint8_t b) {
    if (used_ + 1 > sizeof buffer_) Flush();
    buffer_[used_++] = b;
  }
  void Flush() {
    if (used_ > 0) XXH3_64bits_update(&xxh_, buffer_, used_);
    used_ = 0;
  }

  XXH3_state_t xxh_;
  unsigned char buffer_[1024];
  std::size_t used_ = 0;
};

}  // namespace

std::uint64_t CalcStateHash(const StationState& state) {
  HashVisitor h;
  const std::uint32_t version = kStateHashVersion;
  h("version", &version, 1);
  VisitStationState(state, h);
  return h.Digest();
}

}  // namespace microdex::state
