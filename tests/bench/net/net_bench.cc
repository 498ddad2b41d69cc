// microdex-bench net: 4 stations + 1 instructor on one host, on the loopback profile.
// Reports the haptic period (p99, p99.9, max over the stations, overruns), the
// station→instructor state latency, DeviceInput loss at 1 kHz and the instructor's CPU use.
// With several --scene options the stations take them in turn (mixed classes: needle, thread,
// tissue); each station's period and its modules' step times are listed too.
//
// The stations are microdex-station processes (next to this binary); this process is the
// instructor (microdex::instructor::Instructor), so its CPU use is the instructor's.
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

#include "bench_registry.h"
#include "bench_util.h"
#include "instructor/instructor.h"

namespace microdex::bench {
namespace {

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(i, v.size() - 1)];
}

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

int RunNet(int argc, char** argv) {
  std::string json_path;
  double duration_s = 60;
  int stations = 4;
  int domain = 90;
  std::vector<std::string> scenes;
  CLI::App app{"microdex-bench net: haptic period, DDS latency and loss, 4 stations + instructor"};
  app.add_option("--json", json_path, "write the results as JSON to FILE");
  app.add_option("--duration", duration_s, "seconds of measurement (default 60)");
  app.add_option("--stations", stations, "station processes (default 4)");
  app.add_option("--domain", domain, "DDS domain id (default 90)");
  app.add_option("--scene", scenes,
                 "scene, repeatable: stations take them in turn (default "
                 "assets/scenes/needle_tube.yaml)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "microdex-bench net: %s\n", e.what());
    return 2;
  }
  if (!(duration_s >= 1) || stations < 1 || stations > 16) {
    std::fprintf(stderr, "microdex-bench net: --duration >= 1 s and --stations 1..16 expected\n");
    return 2;
  }
  if (scenes.empty()) {
    const char* src = std::getenv("MICRODEX_SOURCE_DIR");
    scenes.push_back(std::string(src ? src : MICRODEX_BENCH_SOURCE_DIR) +
                     "/assets/scenes/needle_tube.yaml");
  }
  const std::string dir = "/tmp/microdex-bench-net-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);

  instructor::InstructorOptions o;
  o.dds.profile_file = net::DefaultDdsProfileFile();
  o.dds.domain_id = domain;
  o.issuer = "bench";
  o.record_latency = true;
  o.receive_inputs = true;  // the DeviceInput loss is part of the report
  instructor::Instructor console(o);

  // Stations run for the measured duration plus a second of start-up.
  std::vector<pid_t> pids;
  for (int i = 0; i < stations; ++i) {
    const std::string id = "bench-" + std::to_string(i + 1);
    const pid_t pid = fork();
    if (pid == 0) {
      const std::string log = dir + "/" + id + ".log";
      FILE* f = std::fopen(log.c_str(), "w");
      if (f) {
        dup2(fileno(f), 1);
        dup2(fileno(f), 2);
      }
      const std::string bin = SelfDir() + "/microdex-station";
      const std::string dur = std::to_string(duration_s + 1);
      const std::string dom = std::to_string(domain);
      const std::string skill = std::to_string(0.25 * (i % 5));
      const std::string out = dir + "/" + id + ".json";
      const std::string& scene = scenes[static_cast<std::size_t>(i) % scenes.size()];
      execl(bin.c_str(), bin.c_str(), "--scene", scene.c_str(), "--station-id", id.c_str(),
            "--duration", dur.c_str(), "--domain", dom.c_str(), "--skill", skill.c_str(),
            "--score-out", out.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    pids.push_back(pid);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = CpuSeconds();
  for (int status = 0; const pid_t p : pids) {
    waitpid(p, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      std::fprintf(stderr, "microdex-bench net: a station failed (logs in %s)\n", dir.c_str());
      return 1;
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the last samples
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double instructor_cpu = (CpuSeconds() - cpu0) / wall;

  double p99 = 0, p999 = 0, pmax = 0, overruns = 0, lost = 0, steps = 0, received = 0;
  bool realtime = true;
  std::string per_station;  // JSON array items
  for (int i = 0; i < stations; ++i) {
    const std::string id = "bench-" + std::to_string(i + 1);
    std::ifstream f(dir + "/" + id + ".json");
    std::stringstream ss;
    ss << f.rdbuf();
    const std::string j = ss.str();
    p99 = std::max(p99, JsonNumber(j, "period_p99_ms"));
    p999 = std::max(p999, JsonNumber(j, "period_p999_ms"));
    pmax = std::max(pmax, JsonNumber(j, "period_max_ms"));
    overruns += JsonNumber(j, "overruns");
    steps += JsonNumber(j, "steps");
    realtime = realtime && j.find("\"realtime\": true") != std::string::npos;
    {
      const std::string& scene = scenes[static_cast<std::size_t>(i) % scenes.size()];
      std::string modules = "[]";  // the station's own list (name, step mean/p99/max µs, error)
      if (const auto at = j.find("\"modules\": ["); at != std::string::npos) {
        const auto end = j.find("],", at);
        if (end != std::string::npos) modules = j.substr(at + 11, end + 1 - (at + 11));
      }
      char line[512];
      std::snprintf(line, sizeof line,
                    "%s\n    {\"id\": \"%s\", \"scene\": \"%s\", \"period_p99_ms\": %.4f, "
                    "\"period_p999_ms\": %.4f, \"period_max_ms\": %.4f, \"overruns\": %.0f, "
                    "\"modules\": ",
                    per_station.empty() ? "" : ",", id.c_str(),
                    scene.substr(scene.rfind('/') + 1).c_str(), JsonNumber(j, "period_p99_ms"),
                    JsonNumber(j, "period_p999_ms"), JsonNumber(j, "period_max_ms"),
                    JsonNumber(j, "overruns"));
      per_station += line + modules + "}";
    }
    // Lost inputs: dropped before publication (ring, writer) and gaps in the instructor's
    // received step sequence.
    lost += JsonNumber(j, "ring_dropped") + JsonNumber(j, "input_write_failed");
    const auto v = console.Station(id);
    if (v) {
      lost += static_cast<double>(v->inputs_lost);
      received += static_cast<double>(v->inputs_received);
    }
  }
  const instructor::LatencySamples lat = console.TakeLatency();
  char out[2048];
  std::snprintf(
      out, sizeof out,
      "{\n  \"stations\": %d,\n  \"duration_s\": %.1f,\n  \"period_p99_ms\": %.4f,\n"
      "  \"period_p999_ms\": %.4f,\n  \"period_max_ms\": %.4f,\n  \"overruns\": %.0f,\n"
      "  \"latency_p50_us\": %.1f,\n  \"latency_p99_us\": %.1f,\n"
      "  \"transport_latency_p50_us\": %.1f,\n  \"transport_latency_p99_us\": %.1f,\n"
      "  \"latency_samples\": %zu,\n  \"input_lost\": %.0f,\n  \"input_received\": %.0f,\n"
      "  \"station_steps\": %.0f,\n  \"instructor_cpu\": %.3f,\n  \"realtime\": %s,\n",
      stations, duration_s, p99, p999, pmax, overruns, Quantile(lat.state_age_us, 0.5),
      Quantile(lat.state_age_us, 0.99), Quantile(lat.transport_us, 0.5),
      Quantile(lat.transport_us, 0.99), lat.state_age_us.size(), lost, received, steps,
      instructor_cpu, realtime ? "true" : "false");
  std::string by_topic;
  for (const auto& [topic, ages] : lat.state_age_us_by_topic) {
    char item[160];
    std::snprintf(item, sizeof item, "%s\"%s\": {\"p50_us\": %.1f, \"p99_us\": %.1f, \"n\": %zu}",
                  by_topic.empty() ? "" : ", ", topic.c_str(), Quantile(ages, 0.5),
                  Quantile(ages, 0.99), ages.size());
    by_topic += item;
  }
  const std::string report = std::string(out) + "  \"latency_by_topic\": {" + by_topic +
                             "},\n  \"per_station\": [" + per_station + "\n  ]\n}\n";
  std::fputs(report.c_str(), stdout);
  std::printf(
      "goals: period p99 <= 1.1 ms: %s; p99.9 <= 2 ms: %s; latency p50 <= 200 us: %s; "
      "p99 <= 2 ms: %s; zero loss: %s; instructor < 1 core: %s (max is reported, not a goal)\n",
      p99 <= 1.1 ? "met" : "NOT met", p999 <= 2 ? "met" : "NOT met",
      Quantile(lat.state_age_us, 0.5) <= 200 ? "met" : "NOT met",
      Quantile(lat.state_age_us, 0.99) <= 2000 ? "met" : "NOT met", lost == 0 ? "met" : "NOT met",
      instructor_cpu < 1 ? "met" : "NOT met");
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench net: --json '%s': cannot write\n", json_path.c_str());
      return 2;
    }
    f << report;
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(net, "net", "4 stations + instructor over DDS: period, latency, loss, CPU",
                        RunNet);

}  // namespace microdex::bench
