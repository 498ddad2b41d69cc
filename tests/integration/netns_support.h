#pragma once
// Support of the fault tests, on loopback and on the virtual network of netns_run.sh: the
// namespaces and addresses it made, processes started in a namespace, the WAN profiles for
// each host, and what a recording holds of a station.

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/record/recorded_topics.h"
#include "common/record/session_reader.h"
#include "tests/integration/process.h"

namespace microdex::testing {

inline std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

// True inside netns_run.sh (the test binary runs in the instructor's namespace).
inline bool OnVirtualNetwork() { return !Env("MICRODEX_NETNS_IN").empty(); }

// Starts `path` with args inside network namespace `ns` (ip netns exec replaces itself by the
// program: the pid is the program's); output appended to log_path.
inline pid_t SpawnIn(const std::string& ns, const std::string& path,
                     const std::vector<std::string>& args, const std::string& log_path) {
  const pid_t pid = fork();
  if (pid == 0) {
    FILE* log = std::fopen(log_path.c_str(), "a");
    if (log) {
      dup2(fileno(log), 1);
      dup2(fileno(log), 2);
    }
    std::vector<std::string> all{"ip", "netns", "exec", ns, path};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    execvp("ip", argv.data());
    _exit(127);
  }
  return pid;
}

// Runs a shell command; true when it exits 0.
inline bool Shell(const std::string& command) { return std::system(command.c_str()) == 0; }

inline std::string MakeTempDir(const char* stem) {
  std::string dir = std::string("/tmp/") + stem + "-XXXXXX";
  return mkdtemp(dir.data()) ? dir : "/tmp";
}

// Writes DIR/server.xml, instructor.xml, station.xml for the discovery server at ds_address.
inline void WriteWanProfiles(const std::string& dir, const std::string& ds_address) {
  const std::string gen = SourceDir() + "/deploy/dds/gen-profiles";
  for (const char* role : {"server", "instructor", "station"}) {
    const char* transport = std::getenv("MICRODEX_WAN_TRANSPORT");
    // With TCP: a station may listen on a port of its own (deploy/README.md, TCP).
    const char* listen = std::getenv("MICRODEX_WAN_STATION_LISTEN");
    const bool station_listens = listen != nullptr && std::string(role) == "station";
    ASSERT_TRUE(Shell(gen + " --wan " + role + " --server " + ds_address + ":11811" +
                      (transport != nullptr ? std::string(" --transport ") + transport : "") +
                      (station_listens ? std::string(" --listen ") + listen : "") + " > " + dir +
                      "/" + role + ".xml"))
        << role;
  }
}

// The DeviceInput steps of `station` in a recording, in recorded order, and the receive time
// of the last one.
struct RecordedInputs {
  std::vector<std::uint64_t> steps;
  std::int64_t last_receive_ns = 0;
  std::vector<std::string> problems;
  std::map<std::string, std::string> metadata;

  // Steps missing between the first and the last recorded one.
  std::uint64_t Missing() const {
    if (steps.empty()) return 0;
    std::vector<std::uint64_t> s = steps;
    std::sort(s.begin(), s.end());
    s.erase(std::unique(s.begin(), s.end()), s.end());
    return (s.back() - s.front() + 1) - s.size();
  }
};

inline RecordedInputs ReadRecordedInputs(const std::string& file, const std::string& station) {
  RecordedInputs out;
  record::SessionReader reader(file);
  record::MessageFilter filter;
  filter.topic = static_cast<int>(record::TopicIndex::kDeviceInput);
  filter.station = station;
  reader.ForEach(filter, [&](const record::MessageView& m) {
    out.steps.push_back(m.step);
    out.last_receive_ns = m.receive_ns;
    return true;
  });
  out.problems = reader.problems();
  out.metadata = reader.metadata();
  return out;
}

// Messages of `topic` from `station` in a recording.
inline std::size_t CountRecorded(const std::string& file, record::TopicIndex topic,
                                 const std::string& station) {
  record::SessionReader reader(file);
  record::MessageFilter filter;
  filter.topic = static_cast<int>(topic);
  filter.station = station;
  return reader.ForEach(filter, [](const record::MessageView&) { return true; });
}

}  // namespace microdex::testing
