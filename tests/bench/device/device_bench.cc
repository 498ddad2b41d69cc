// microdex-bench device: the round trip of the DDS device bridge, pose → station tick → force
// back at the driver, with other stations running on the same host. One station process runs
// with --device dds; --others more run simulated trainees (the load of a class); this process
// is the driver (station/device_driver.h): 1 kHz samples, each answered by the force of the
// tick that read it (the sample's stamp comes back in the force). Reported: round trip p50,
// p99 and max (µs), samples sent and lost (never answered: the station read a later one),
// the station's own period p99 and CPU time, and where the round trip goes (the median of
// each hop, from the stamps the bridge records under MICRODEX_DEVICE_HOPS and the driver's);
// goals p50 <= 150 µs, p99 <= 500 µs on shared memory.
//
// --compare BASE:NEW runs --rounds rounds of each bridge tuning (station/dds_bridge_tuning.h;
// both ends use it), alternating BASE and NEW, and reports the median over the rounds of each
// one's p50, p99 and hops, and the ratios NEW / BASE.
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_registry.h"
#include "bench_util.h"
#include "common/net/dds_context.h"
#include "station/dds_device.h"
#include "station/device_driver.h"

namespace microdex::bench {
namespace {

// The hops of the round trip, in order; their medians add up to about the round trip's.
constexpr std::array<const char*, 6> kHops = {
    "to_listener",   // the driver's write → the station's listener has the sample
    "to_tick",       // → the haptic thread's wait returns
    "tick",          // → the force is computed (Read, StepStation, WriteForce)
    "to_publisher",  // → the bridge's publisher thread is awake with it
    "publish",       // → the write starts (the force's stamp)
    "to_driver",     // → the driver's listener has the force
};

struct RunSpec {
  std::string scene;
  double duration_s = 10;
  int others = 3;
  int domain = 91;
  station::DdsBridgeTuning tuning;
};

struct RunResult {
  bool ok = false;
  double p50 = NAN, p99 = NAN, max = NAN;
  std::uint64_t sent = 0, lost = 0, forces = 0;
  double period_p99_ms = NAN;
  double station_cpu = NAN;  // the dds station's CPU time per wall second, all its threads
  int driver_dds_threads_rt = 0;
  std::size_t hops_joined = 0;
  std::map<std::string, double> hop_p50, hop_p99;  // µs
  double driver_write_p50 = NAN;                   // µs: the driver's write call
  double station_write_p50 = NAN;                  // µs: the bridge's write call
};

pid_t StartStation(const std::string& dir, const std::string& id, const RunSpec& spec,
                   double duration_s, bool dds_device) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (dds_device) setenv(station::DdsDevice::kHopsEnv, dir.c_str(), 1);
    const std::string log = dir + "/" + id + ".log";
    FILE* f = std::fopen(log.c_str(), "w");
    if (f) {
      dup2(fileno(f), 1);
      dup2(fileno(f), 2);
    }
    const std::string bin = SelfDir() + "/microdex-station";
    const std::string dur = std::to_string(duration_s);
    const std::string dom = std::to_string(spec.domain);
    const std::string out = dir + "/" + id + ".json";
    const std::string tuning = spec.tuning.Name();
    if (dds_device) {
      execl(bin.c_str(), bin.c_str(), "--scene", spec.scene.c_str(), "--station-id", id.c_str(),
            "--duration", dur.c_str(), "--domain", dom.c_str(), "--device", "dds",
            "--device-bridge-tuning", tuning.c_str(), "--score-out", out.c_str(),
            static_cast<char*>(nullptr));
    } else {
      execl(bin.c_str(), bin.c_str(), "--scene", spec.scene.c_str(), "--station-id", id.c_str(),
            "--duration", dur.c_str(), "--domain", dom.c_str(), "--score-out", out.c_str(),
            static_cast<char*>(nullptr));
    }
    _exit(127);
  }
  return pid;
}

double LoadAverage1() {
  double load = NAN;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &load) != 1) load = NAN;
    std::fclose(f);
  }
  return load;
}

// The bridge's hop records (DdsDevice::Hops, KEY.hops.csv) by sample step.
std::map<std::uint64_t, station::DdsDevice::Hops> ReadStationHops(const std::string& path) {
  std::map<std::uint64_t, station::DdsDevice::Hops> hops;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    station::DdsDevice::Hops h{};
    unsigned long long step = 0;
    long long v[7];
    if (std::sscanf(line.c_str(), "%llu,%lld,%lld,%lld,%lld,%lld,%lld,%lld", &step, &v[0], &v[1],
                    &v[2], &v[3], &v[4], &v[5], &v[6]) != 8) {
      continue;
    }
    h.sample_step = step;
    h.sample_stamp_ns = v[0];
    h.received_ns = v[1];
    h.woken_ns = v[2];
    h.ready_ns = v[3];
    h.publisher_woken_ns = v[4];
    h.write_ns = v[5];
    h.written_ns = v[6];
    hops.emplace(step, h);  // the first force that answered the sample
  }
  return hops;
}

// Joins the driver's answered samples with the bridge's records of the forces that answered
// them and takes the median and p99 of each hop.
void SummariseHops(const station::DriverStats& s, const std::string& station_hops_path,
                   RunResult& r) {
  const auto station = ReadStationHops(station_hops_path);
  std::map<std::string, std::vector<double>> us;
  std::vector<double> driver_write, station_write;
  for (const station::DriverHop& d : s.hops) {
    const auto it = station.find(d.sample_step);
    if (it == station.end()) continue;
    const station::DdsDevice::Hops& h = it->second;
    if (h.sample_stamp_ns != d.sample_stamp_ns || h.write_ns != d.force_stamp_ns) continue;
    const std::int64_t publisher = std::max(h.publisher_woken_ns, h.ready_ns);
    const std::array<std::int64_t, 7> t = {d.sample_stamp_ns, h.received_ns, h.woken_ns,
                                           h.ready_ns,        publisher,     h.write_ns,
                                           d.received_ns};
    for (std::size_t i = 0; i < kHops.size(); ++i) {
      us[kHops[i]].push_back(static_cast<double>(t[i + 1] - t[i]) * 1e-3);
    }
    if (d.write_returned_ns > 0) {
      driver_write.push_back(static_cast<double>(d.write_returned_ns - d.sample_stamp_ns) * 1e-3);
    }
    station_write.push_back(static_cast<double>(h.written_ns - h.write_ns) * 1e-3);
  }
  r.hops_joined = station_write.size();
  for (const char* name : kHops) {
    r.hop_p50[name] = station::Quantile(us[name], 0.5);
    r.hop_p99[name] = station::Quantile(us[name], 0.99);
  }
  r.driver_write_p50 = station::Quantile(driver_write, 0.5);
  r.station_write_p50 = station::Quantile(station_write, 0.5);
}

RunResult RunOnce(const RunSpec& spec, int round) {
  RunResult r;
  const std::string dir =
      "/tmp/microdex-bench-device-" + std::to_string(getpid()) + "-" + std::to_string(round);
  mkdir(dir.c_str(), 0755);
  // Every process stops by itself: the stations after their duration, the driver after its.
  const double station_s = spec.duration_s + 4;  // start-up and discovery
  std::vector<pid_t> pids;
  const std::string id = "bench-device-" + std::to_string(getpid());
  const auto started = std::chrono::steady_clock::now();
  pids.push_back(StartStation(dir, id, spec, station_s, true));
  for (int i = 0; i < spec.others; ++i) {
    pids.push_back(StartStation(dir, id + "-other-" + std::to_string(i), spec, station_s, false));
  }
  station::DeviceDriverDef def;
  def.station_id = id;
  def.duration_s = spec.duration_s;
  def.discovery_timeout_s = 3;
  def.tuning = spec.tuning;
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = spec.domain;
  dds.participant_name = "microdex-bench-device";
  station::DriverStats s;
  bool failed = false;
  try {
    const std::atomic<bool> stop{false};
    s = station::RunDeviceDriver(dds, def, stop);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-bench device: %s\n", e.what());
    failed = true;
  }
  for (int status = 0; const pid_t p : pids) {
    rusage ru{};
    wait4(p, &status, 0, &ru);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      std::fprintf(stderr, "microdex-bench device: a station failed (logs in %s)\n", dir.c_str());
      failed = true;
    }
    if (p == pids.front()) {
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      const double cpu = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                         static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
      r.station_cpu = cpu / wall;
    }
  }
  if (failed) return r;
  if (!s.matched) {
    std::fprintf(stderr, "microdex-bench device: the station's bridge was not found (%s)\n",
                 dir.c_str());
    return r;
  }
  r.p50 = station::Quantile(s.round_trip_us, 0.5);
  r.p99 = station::Quantile(s.round_trip_us, 0.99);
  r.max = station::Quantile(s.round_trip_us, 1.0);
  r.sent = s.sent;
  r.lost = s.lost;
  r.forces = s.forces;
  r.driver_dds_threads_rt = s.dds_threads_realtime;
  r.period_p99_ms = JsonNumber(ReadText(dir + "/" + id + ".json"), "period_p99_ms");
  SummariseHops(s, dir + "/" + id + ".hops.csv", r);
  r.ok = true;
  return r;
}

void PrintRun(const RunSpec& spec, const RunResult& r) {
  std::printf(
      "device bridge (tuning %s), %d other stations, %.0f s: round trip p50 %.0f us (goal <= "
      "150), p99 %.0f us (goal <= 500), max %.0f us; sent %llu, lost %llu; station period p99 "
      "%.3f ms, CPU %.1f %%\n  hops (median us):",
      spec.tuning.Name().c_str(), spec.others, spec.duration_s, r.p50, r.p99, r.max,
      static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.lost),
      r.period_p99_ms, 100 * r.station_cpu);
  for (const char* name : kHops) std::printf(" %s %.1f", name, r.hop_p50.at(name));
  std::printf(" (of %zu samples; write calls: driver %.1f, station %.1f)\n", r.hops_joined,
              r.driver_write_p50, r.station_write_p50);
}

std::string HopsJson(const std::map<std::string, double>& m) {
  std::ostringstream o;
  o << "{";
  for (std::size_t i = 0; i < kHops.size(); ++i) {
    o << (i ? ", " : "") << "\"" << kHops[i] << "\": " << m.at(kHops[i]);
  }
  o << "}";
  return o.str();
}

double Median(std::vector<double> v) { return station::Quantile(std::move(v), 0.5); }

// The median over rounds of each figure of one tuning's runs.
RunResult MedianOf(const std::vector<RunResult>& runs) {
  RunResult m;
  auto med = [&](auto field) {
    std::vector<double> v;
    for (const RunResult& r : runs) v.push_back(static_cast<double>(field(r)));
    return Median(v);
  };
  m.ok = true;
  m.p50 = med([](const RunResult& r) { return r.p50; });
  m.p99 = med([](const RunResult& r) { return r.p99; });
  m.max = med([](const RunResult& r) { return r.max; });
  m.sent = static_cast<std::uint64_t>(med([](const RunResult& r) { return r.sent; }));
  m.lost = static_cast<std::uint64_t>(med([](const RunResult& r) { return r.lost; }));
  m.forces = static_cast<std::uint64_t>(med([](const RunResult& r) { return r.forces; }));
  m.period_p99_ms = med([](const RunResult& r) { return r.period_p99_ms; });
  m.station_cpu = med([](const RunResult& r) { return r.station_cpu; });
  m.driver_write_p50 = med([](const RunResult& r) { return r.driver_write_p50; });
  m.station_write_p50 = med([](const RunResult& r) { return r.station_write_p50; });
  m.hops_joined = static_cast<std::size_t>(med([](const RunResult& r) { return r.hops_joined; }));
  for (const char* name : kHops) {
    m.hop_p50[name] = med([&](const RunResult& r) { return r.hop_p50.at(name); });
    m.hop_p99[name] = med([&](const RunResult& r) { return r.hop_p99.at(name); });
  }
  return m;
}

std::string RunJson(const RunResult& r, const std::string& indent) {
  std::ostringstream o;
  o << "{\n"
    << indent << "  \"round_trip_us\": {\"p50\": " << r.p50 << ", \"p99\": " << r.p99
    << ", \"max\": " << r.max << "},\n"
    << indent << "  \"sent\": " << r.sent << ",\n"
    << indent << "  \"lost\": " << r.lost << ",\n"
    << indent << "  \"forces\": " << r.forces << ",\n"
    << indent << "  \"station_period_p99_ms\": " << r.period_p99_ms << ",\n"
    << indent << "  \"station_cpu\": " << r.station_cpu << ",\n"
    << indent << "  \"hops_p50_us\": " << HopsJson(r.hop_p50) << ",\n"
    << indent << "  \"hops_p99_us\": " << HopsJson(r.hop_p99) << ",\n"
    << indent << "  \"write_call_p50_us\": {\"driver\": " << r.driver_write_p50
    << ", \"station\": " << r.station_write_p50 << "}\n"
    << indent << "}";
  return o.str();
}

int RunDevice(int argc, char** argv) {
  std::string json_path;
  RunSpec spec;
  std::string tuning = "all";
  std::string compare;
  int rounds = 3;
  CLI::App app{"microdex-bench device: DDS device bridge round trip with other stations running"};
  app.add_option("--json", json_path, "write the results as JSON to FILE");
  app.add_option("--duration", spec.duration_s, "seconds of measurement per run (default 10)");
  app.add_option("--others", spec.others, "other (simulated) stations running (default 3)");
  app.add_option("--domain", spec.domain, "DDS domain id (default 91)");
  app.add_option("--scene", spec.scene, "scene of every station (default needle_tube.yaml)");
  app.add_option("--tuning", tuning,
                 "bridge tuning of both ends: all (default), none, or a comma list of shm, rt");
  app.add_option("--compare", compare,
                 "BASE:NEW: alternate runs of two tunings (e.g. none:all) and report the "
                 "medians over the rounds and the ratios NEW/BASE");
  app.add_option("--rounds", rounds, "--compare: runs of each tuning (default 3)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "microdex-bench device: %s\n", e.what());
    return 2;
  }
  if (!(spec.duration_s >= 1 && spec.duration_s <= 600) || spec.others < 0 || spec.others > 8 ||
      rounds < 1 || rounds > 20) {
    std::fprintf(stderr,
                 "microdex-bench device: --duration 1..600 s, --others 0..8, --rounds 1..20 "
                 "expected\n");
    return 2;
  }
  if (spec.scene.empty()) {
    const char* src = std::getenv("MICRODEX_SOURCE_DIR");
    spec.scene =
        std::string(src ? src : MICRODEX_BENCH_SOURCE_DIR) + "/assets/scenes/needle_tube.yaml";
  }
  station::DdsBridgeTuning base, tuned;
  if (compare.empty()) {
    if (const std::string why = station::DdsBridgeTuning::Parse(tuning, &tuned); !why.empty()) {
      std::fprintf(stderr, "microdex-bench device: --tuning %s\n", why.c_str());
      return 2;
    }
  } else {
    const auto colon = compare.find(':');
    std::string why = colon == std::string::npos ? "'" + compare + "': expected BASE:NEW" : "";
    if (why.empty()) why = station::DdsBridgeTuning::Parse(compare.substr(0, colon), &base);
    if (why.empty()) why = station::DdsBridgeTuning::Parse(compare.substr(colon + 1), &tuned);
    if (!why.empty()) {
      std::fprintf(stderr, "microdex-bench device: --compare %s\n", why.c_str());
      return 2;
    }
  }
  const double load_before = LoadAverage1();

  if (compare.empty()) {
    spec.tuning = tuned;
    const RunResult r = RunOnce(spec, 0);
    if (!r.ok) return 2;
    PrintRun(spec, r);
    const double load_after = LoadAverage1();
    std::printf("  load average (1 min) %.2f before, %.2f after\n", load_before, load_after);
    if (!json_path.empty()) {
      std::ofstream f(json_path);
      if (!f) {
        std::fprintf(stderr, "microdex-bench device: --json '%s': cannot write\n",
                     json_path.c_str());
        return 2;
      }
      const std::string run = RunJson(r, "");
      // The run's fields at the top level, then the context.
      f << run.substr(0, run.size() - 2) << ",\n  \"tuning\": \"" << tuned.Name()
        << "\",\n  \"other_stations\": " << spec.others
        << ",\n  \"duration_s\": " << spec.duration_s << ",\n  \"load_average\": [" << load_before
        << ", " << load_after << "],\n  \"goals\": {\"p50_us\": 150, \"p99_us\": 500}\n}\n";
    }
    return 0;
  }

  std::vector<RunResult> base_runs, tuned_runs;
  for (int i = 0; i < rounds; ++i) {
    for (int which = 0; which < 2; ++which) {
      spec.tuning = which == 0 ? base : tuned;
      const RunResult r = RunOnce(spec, 2 * i + which);
      if (!r.ok) return 2;
      std::printf("round %d ", i + 1);
      PrintRun(spec, r);
      std::fflush(stdout);
      (which == 0 ? base_runs : tuned_runs).push_back(r);
    }
  }
  const RunResult b = MedianOf(base_runs);
  const RunResult t = MedianOf(tuned_runs);
  auto spread = [](const std::vector<RunResult>& runs, double RunResult::*field) {
    double lo = INFINITY, hi = -INFINITY;
    for (const RunResult& r : runs) {
      lo = std::min(lo, r.*field);
      hi = std::max(hi, r.*field);
    }
    return std::pair<double, double>(lo, hi);
  };
  const double load_after = LoadAverage1();
  std::printf("median of %d rounds, %d other stations, %.0f s each; load average %.2f → %.2f\n",
              rounds, spec.others, spec.duration_s, load_before, load_after);
  for (const auto& [name, runs, m] :
       {std::tuple<std::string, const std::vector<RunResult>&, const RunResult&>{base.Name(),
                                                                                 base_runs, b},
        {tuned.Name(), tuned_runs, t}}) {
    const auto [p50_lo, p50_hi] = spread(runs, &RunResult::p50);
    const auto [p99_lo, p99_hi] = spread(runs, &RunResult::p99);
    std::printf(
        "  %-7s p50 %.0f us (%.0f..%.0f), p99 %.0f us (%.0f..%.0f), lost %llu, CPU %.1f %%; "
        "hops:",
        name.c_str(), m.p50, p50_lo, p50_hi, m.p99, p99_lo, p99_hi,
        static_cast<unsigned long long>(m.lost), 100 * m.station_cpu);
    for (const char* hop : kHops) std::printf(" %s %.1f", hop, m.hop_p50.at(hop));
    std::printf("\n");
  }
  std::printf("  ratio %s/%s: p50 %.2f, p99 %.2f\n", tuned.Name().c_str(), base.Name().c_str(),
              t.p50 / b.p50, t.p99 / b.p99);
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench device: --json '%s': cannot write\n", json_path.c_str());
      return 2;
    }
    // The new tuning's medians at the top level (the fields of a single run), then both.
    const std::string run = RunJson(t, "");
    f << run.substr(0, run.size() - 2) << ",\n  \"tuning\": \"" << tuned.Name()
      << "\",\n  \"other_stations\": " << spec.others << ",\n  \"duration_s\": " << spec.duration_s
      << ",\n  \"load_average\": [" << load_before << ", " << load_after
      << "],\n  \"compare\": {\n    \"rounds\": " << rounds << ",\n    \"base\": \"" << base.Name()
      << "\",\n    \"new\": \"" << tuned.Name()
      << "\",\n    \"base_median\": " << RunJson(b, "    ")
      << ",\n    \"new_median\": " << RunJson(t, "    ")
      << ",\n    \"ratio_p50\": " << t.p50 / b.p50 << ",\n    \"ratio_p99\": " << t.p99 / b.p99
      << "\n  },\n  \"goals\": {\"p50_us\": 150, \"p99_us\": 500}\n}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(device, "device",
                        "DDS device bridge: pose → station tick → force round trip, hops, lost "
                        "samples; --compare two bridge tunings",
                        RunDevice);

}  // namespace microdex::bench
