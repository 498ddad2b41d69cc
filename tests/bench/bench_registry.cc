#include "bench_registry.h"

namespace microdex::bench {

std::vector<BenchCommand>& Registry() {
  static std::vector<BenchCommand> registry;
  return registry;
}

}  // namespace microdex::bench
