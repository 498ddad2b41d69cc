#pragma once
// The DDS options every app takes, on a CLI11 command line (header only: include from the apps,
// which link CLI11), and the one way the apps parse their command line.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <optional>

#include "common/net/dds_context.h"

namespace microdex::net {

// --dds-profile FILE, --domain N, --partition COURSE (the course).
inline void AddDdsOptions(CLI::App& app, DdsOptions& dds) {
  app.add_option("--dds-profile", dds.profile_file, "DDS XML profiles")->capture_default_str();
  app.add_option("--domain", dds.domain_id, "DDS domain id");
  app.add_option("--partition", dds.partition, "DDS partition (the course)");
}

// Parses; on --help returns 0 after printing it, on bad input prints "PROGRAM: reason" and
// returns 2 (the exit status of bad input); nullopt when the app should go on.
inline std::optional<int> ParseCommandLine(CLI::App& app, int argc, char** argv,
                                           const char* program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return 2;
  }
  return std::nullopt;
}

}  // namespace microdex::net
