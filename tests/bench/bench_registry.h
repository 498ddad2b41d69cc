#pragma once
// Subcommands of microdex-bench register themselves here at static-initialisation time,
// so each report lives in its own folder and main.cc needs no list of them.

#include <functional>
#include <string>
#include <vector>

namespace microdex::bench {

// A report: `run` gets the arguments after the subcommand name (argv[0] is the
// subcommand) and returns the process exit status (0 ok, 2 bad input).
struct BenchCommand {
  std::string name;
  std::string summary;
  std::function<int(int argc, char** argv)> run;
};

std::vector<BenchCommand>& Registry();

struct BenchRegistrar {
  explicit BenchRegistrar(BenchCommand command) { Registry().push_back(std::move(command)); }
};

}  // namespace microdex::bench

// Use once per report, at namespace scope in its .cc file.
#define MICRODEX_REGISTER_BENCH(ident, name, summary, fn) \
  static const ::microdex::bench::BenchRegistrar ident##_registrar({name, summary, fn})
