#pragma once
// What every app's main shares (header only: include from the apps, which link CLI11): the DDS
// options on a CLI11 command line, the one way the apps parse their command line, and the one
// way they stop on SIGINT/SIGTERM.

#include <pthread.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <optional>
#include <thread>

#include "common/net/dds_context.h"
#include "common/net/dds_security.h"

namespace microdex::net {

// --dds-profile FILE, --domain N, --partition COURSE (the course).
inline void AddDdsOptions(CLI::App& app, DdsOptions& dds) {
  app.add_option("--dds-profile", dds.profile_file, "DDS XML profiles")->capture_default_str();
  app.add_option("--domain", dds.domain_id, "DDS domain id");
  app.add_option("--partition", dds.partition, "DDS partition (the course)");
}

// --security DIR: DDS Security with the identity directory DIR (deploy/security/make-course).
inline void AddSecurityOption(CLI::App& app, DdsOptions& dds) {
  app.add_option("--security", dds.security_dir,
                 "DDS Security: this participant's identity directory (deploy/security/make-course"
                 "); authenticated, access-controlled, encrypted DDS in the course's partitions");
}

// The --security directory checked (dds_security.h) before anything starts: empty when
// valid or not given, else "--security: reason" naming the file.
inline std::string CheckSecurityOption(const DdsOptions& dds) {
  if (dds.security_dir.empty()) return {};
  try {
    LoadSecurityFiles(dds.security_dir);
  } catch (const std::exception& e) {
    return std::string("--security: ") + e.what();
  }
  return {};
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

// SIGINT and SIGTERM blocked in every thread and taken by one watcher thread that only sets a
// stop flag. Construct it first in main: the threads started later (DDS's among them) inherit
// the mask, so no signal lands in a thread that cannot stop the app.
class StopSignals {
 public:
  StopSignals() {
    sigemptyset(&signals_);
    sigaddset(&signals_, SIGINT);
    sigaddset(&signals_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
  }
  // Starts the watcher; it ends with the process and only ever sets `stop`.
  void Watch(std::atomic<bool>& stop) const {
    std::thread([signals = signals_, &stop] {
      int sig = 0;
      sigwait(&signals, &sig);
      stop = true;
    }).detach();
  }

 private:
  sigset_t signals_{};
};

}  // namespace microdex::net
