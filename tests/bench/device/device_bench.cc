// microdex-bench device: the round trip of the DDS device bridge, pose → station tick → force
// back at the driver, with other stations running on the same host. One station process runs
// with --device dds; --others more run simulated trainees (the load of a class); this process
// is the driver (station/device_driver.h): 1 kHz samples, each answered by the force of the
// tick that read it (the sample's stamp comes back in the force). Reported: round trip p50,
// p99 and max (µs), samples sent and lost (never answered: the station read a later one),
// and the station's own period p99; goals p50 <= 150 µs, p99 <= 500 µs on shared memory.
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_registry.h"
#include "bench_util.h"
#include "common/net/dds_context.h"
#include "station/device_driver.h"

namespace microdex::bench {
namespace {

pid_t StartStation(const std::string& dir, const std::string& id, const std::string& scene,
                   double duration_s, int domain, bool dds_device) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string log = dir + "/" + id + ".log";
    FILE* f = std::fopen(log.c_str(), "w");
    if (f) {
      dup2(fileno(f), 1);
      dup2(fileno(f), 2);
    }
    const std::string bin = SelfDir() + "/microdex-station";
    const std::string dur = std::to_string(duration_s);
    const std::string dom = std::to_string(domain);
    const std::string out = dir + "/" + id + ".json";
    if (dds_device) {
      execl(bin.c_str(), bin.c_str(), "--scene", scene.c_str(), "--station-id", id.c_str(),
            "--duration", dur.c_str(), "--domain", dom.c_str(), "--device", "dds", "--score-out",
            out.c_str(), static_cast<char*>(nullptr));
    } else {
      execl(bin.c_str(), bin.c_str(), "--scene", scene.c_str(), "--station-id", id.c_str(),
            "--duration", dur.c_str(), "--domain", dom.c_str(), "--score-out", out.c_str(),
            static_cast<char*>(nullptr));
    }
    _exit(127);
  }
  return pid;
}

int RunDevice(int argc, char** argv) {
  std::string json_path;
  double duration_s = 10;
  int others = 3;
  int domain = 91;
  std::string scene;
  CLI::App app{"microdex-bench device: DDS device bridge round trip with other stations running"};
  app.add_option("--json", json_path, "write the results as JSON to FILE");
  app.add_option("--duration", duration_s, "seconds of measurement (default 10)");
  app.add_option("--others", others, "other (simulated) stations running (default 3)");
  app.add_option("--domain", domain, "DDS domain id (default 91)");
  app.add_option("--scene", scene, "scene of every station (default needle_tube.yaml)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "microdex-bench device: %s\n", e.what());
    return 2;
  }
  if (!(duration_s >= 1 && duration_s <= 600) || others < 0 || others > 8) {
    std::fprintf(stderr, "microdex-bench device: --duration 1..600 s, --others 0..8 expected\n");
    return 2;
  }
  if (scene.empty()) {
    const char* src = std::getenv("MICRODEX_SOURCE_DIR");
    scene = std::string(src ? src : MICRODEX_BENCH_SOURCE_DIR) + "/assets/scenes/needle_tube.yaml";
  }
  const std::string dir = "/tmp/microdex-bench-device-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  // Every process stops by itself: the stations after their duration, the driver after its.
  const double station_s = duration_s + 4;  // start-up and discovery
  std::vector<pid_t> pids;
  const std::string id = "bench-device-" + std::to_string(getpid());
  pids.push_back(StartStation(dir, id, scene, station_s, domain, true));
  for (int i = 0; i < others; ++i) {
    pids.push_back(
        StartStation(dir, id + "-other-" + std::to_string(i), scene, station_s, domain, false));
  }
  station::DeviceDriverDef def;
  def.station_id = id;
  def.duration_s = duration_s;
  def.discovery_timeout_s = 3;
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = domain;
  dds.participant_name = "microdex-bench-device";
  station::DriverStats s;
  int status_out = 0;
  try {
    const std::atomic<bool> stop{false};
    s = station::RunDeviceDriver(dds, def, stop);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-bench device: %s\n", e.what());
    status_out = 2;
  }
  for (int status = 0; const pid_t p : pids) {
    waitpid(p, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      std::fprintf(stderr, "microdex-bench device: a station failed (logs in %s)\n", dir.c_str());
      status_out = 2;
    }
  }
  if (status_out != 0) return status_out;
  if (!s.matched) {
    std::fprintf(stderr, "microdex-bench device: the station's bridge was not found (%s)\n",
                 dir.c_str());
    return 2;
  }
  const double p50 = station::Quantile(s.round_trip_us, 0.5);
  const double p99 = station::Quantile(s.round_trip_us, 0.99);
  const double pmax = station::Quantile(s.round_trip_us, 1.0);
  const double period_p99_ms = JsonNumber(ReadText(dir + "/" + id + ".json"), "period_p99_ms");
  std::printf(
      "device bridge, %d other stations, %.0f s: round trip p50 %.0f us (goal <= 150), "
      "p99 %.0f us (goal <= 500), max %.0f us; sent %llu, lost %llu; station period "
      "p99 %.3f ms\n",
      others, duration_s, p50, p99, pmax, static_cast<unsigned long long>(s.sent),
      static_cast<unsigned long long>(s.lost), period_p99_ms);
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench device: --json '%s': cannot write\n", json_path.c_str());
      return 2;
    }
    f << "{\n  \"round_trip_us\": {\"p50\": " << p50 << ", \"p99\": " << p99
      << ", \"max\": " << pmax << "},\n  \"sent\": " << s.sent << ",\n  \"lost\": " << s.lost
      << ",\n  \"forces\": " << s.forces << ",\n  \"other_stations\": " << others
      << ",\n  \"duration_s\": " << duration_s
      << ",\n  \"station_period_p99_ms\": " << period_p99_ms
      << ",\n  \"goals\": {\"p50_us\": 150, \"p99_us\": 500}\n}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(device, "device",
                        "DDS device bridge: pose → station tick → force round trip, lost samples",
                        RunDevice);

}  // namespace microdex::bench
