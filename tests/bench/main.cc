// microdex-bench SUBCOMMAND [options]: dispatches to the registered reports.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>

#include "bench_registry.h"

namespace {

void PrintUsage(std::FILE* out) {
  auto commands = microdex::bench::Registry();
  std::sort(commands.begin(), commands.end(),
            [](const auto& a, const auto& b) { return a.name < b.name; });
  std::fprintf(
      out, "usage: microdex-bench SUBCOMMAND [options]   (SUBCOMMAND --help for its options)\n\n");
  for (const auto& command : commands) {
    std::fprintf(out, "  %-8s %s\n", command.name.c_str(), command.summary.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    PrintUsage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  for (const auto& command : microdex::bench::Registry()) {
    if (command.name == argv[1]) {
      try {
        return command.run(argc - 1, argv + 1);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "microdex-bench %s: %s\n", argv[1], e.what());
        return 2;
      }
    }
  }
  std::fprintf(stderr, "microdex-bench: unknown subcommand '%s'\n", argv[1]);
  PrintUsage(stderr);
  return 2;
}
