#pragma once
// Child processes for the integration tests: start a binary of the build, signal it, wait for
// its exit with a deadline. Children inherit the environment (FASTRTPS_DEFAULT_PROFILES_FILE
// points at the loopback-only profile).

#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace microdex::testing {

inline std::string BinDir() {
  const char* env = std::getenv("MICRODEX_BIN_DIR");
  return env ? env : MICRODEX_TEST_BIN_DIR;
}

inline std::string SourceDir() {
  const char* env = std::getenv("MICRODEX_SOURCE_DIR");
  return env ? env : MICRODEX_TEST_SOURCE_DIR;
}

// The fault tests' stations are paced as a station on a machine of its own is: the service
// unit's `--spin-us 100` (deploy/systemd/microdex-station@.service, station/README.md
// "Pacing"). MICRODEX_STATION_SPIN_US overrides it, for comparisons.
inline std::string StationSpinUs() {
  const char* env = std::getenv("MICRODEX_STATION_SPIN_US");
  return env ? env : "100";
}

// Starts BinDir()/binary with args; stdout and stderr go to log_path (appended).
inline pid_t Spawn(const std::string& binary, const std::vector<std::string>& args,
                   const std::string& log_path) {
  const pid_t pid = fork();
  if (pid == 0) {
    FILE* log = std::fopen(log_path.c_str(), "a");
    if (log) {
      dup2(fileno(log), 1);
      dup2(fileno(log), 2);
    }
    std::vector<std::string> all{BinDir() + "/" + binary};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

// Waits up to `timeout` for pid to exit; its exit status (or 128 + signal), nullopt on
// timeout.
inline std::optional<int> WaitExit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) {
      if (WIFEXITED(status)) return WEXITSTATUS(status);
      if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
      return -1;
    }
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Kills and reaps every pid still running (test teardown).
inline void KillAll(const std::vector<pid_t>& pids) {
  for (pid_t p : pids) {
    if (p > 0 && kill(p, 0) == 0) {
      kill(p, SIGKILL);
      waitpid(p, nullptr, 0);
    }
  }
}

// Polls `done` every 10 ms until it holds or `timeout` passes; true when it held.
inline bool WaitUntil(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

inline std::string ReadFile(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return "";
  std::string s;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  std::fclose(f);
  return s;
}

// The number after "key": in a flat JSON text (the score files); NaN when absent.
inline double JsonNumber(const std::string& json, const std::string& key) {
  const auto at = json.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + at + key.size() + 3, nullptr);
}

}  // namespace microdex::testing
