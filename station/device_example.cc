// microdex-device-example: a device driver for the station's DDS device bridge, replaying a
// script (a slow circle) or a CSV of hand samples at 1 kHz and timing the force coming back
// (station/README.md "DDS device bridge").
#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <fstream>

#include "common/net/app_cli.h"
#include "station/device_driver.h"

int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  const microdex::net::StopSignals stop_signals;
  static std::atomic<bool> stop{false};
  microdex::station::DeviceDriverDef def;
  microdex::net::DdsOptions dds;
  dds.profile_file = microdex::net::DefaultDdsProfileFile();
  dds.participant_name = "microdex-device-example";
  std::string fault = "none", stats_json;
  CLI::App app{"microdex-device-example: a driver for the station's DDS device bridge"};
  app.add_option("--station-id", def.station_id, "the station to drive")->required();
  app.add_option("--csv", def.csv, "hand samples (p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons)");
  app.add_option("--duration", def.duration_s, "seconds of sending");
  app.add_option("--rate", def.rate_hz, "samples per second");
  app.add_option("--radius", def.circle_radius_m, "the script's circle radius, m (device frame)");
  app.add_option("--fault", fault, "misbehave on purpose: none, stop, nan, jump");
  app.add_option("--fault-at", def.fault_at_s, "when, s after the start");
  app.add_option("--fault-for", def.fault_for_s, "for how long, s");
  app.add_option("--stats-json", stats_json, "write the round trips and losses as JSON");
  std::string tuning = "all";
  app.add_option("--tuning", tuning,
                 "all (default), none, or a comma list of shm (shared-memory participant "
                 "profile), rt (the participant's DDS threads SCHED_FIFO), cpu (a 0 us PM QoS "
                 "CPU latency request while running)");
  microdex::net::AddDdsOptions(app, dds);
  microdex::net::AddSecurityOption(app, dds);
  if (const std::optional<int> status =
          microdex::net::ParseCommandLine(app, argc, argv, "microdex-device-example")) {
    return *status;
  }
  using microdex::station::DriverFault;
  if (fault == "none") {
    def.fault = DriverFault::kNone;
  } else if (fault == "stop") {
    def.fault = DriverFault::kStop;
  } else if (fault == "nan") {
    def.fault = DriverFault::kNaN;
  } else if (fault == "jump") {
    def.fault = DriverFault::kJump;
  } else {
    std::fprintf(stderr, "microdex-device-example: --fault: expected none|stop|nan|jump\n");
    return 2;
  }
  if (const std::string why = microdex::station::DdsBridgeTuning::Parse(tuning, &def.tuning);
      !why.empty()) {
    std::fprintf(stderr, "microdex-device-example: --tuning %s\n", why.c_str());
    return 2;
  }
  if (const std::string why = def.Validate(); !why.empty()) {
    std::fprintf(stderr, "microdex-device-example: --%s\n", why.c_str());
    return 2;
  }
  dds.security_station = def.station_id;  // with --security: the station's partition
  if (const std::string why = microdex::net::CheckSecurityOption(dds); !why.empty()) {
    std::fprintf(stderr, "microdex-device-example: %s\n", why.c_str());
    return 2;
  }
  stop_signals.Watch(stop);
  try {
    const microdex::station::DriverStats s = microdex::station::RunDeviceDriver(dds, def, stop);
    if (!s.matched) {
      std::fprintf(stderr,
                   "microdex-device-example: station '%s' not found (is it running with "
                   "--device dds?)\n",
                   def.station_id.c_str());
      return 2;
    }
    const double p50 = microdex::station::Quantile(s.round_trip_us, 0.5);
    const double p99 = microdex::station::Quantile(s.round_trip_us, 0.99);
    std::printf(
        "sent %llu, forces %llu, answered %llu, lost %llu, fault forces %llu; round trip "
        "p50 %.0f us, p99 %.0f us; max force %.3f N\n",
        static_cast<unsigned long long>(s.sent), static_cast<unsigned long long>(s.forces),
        static_cast<unsigned long long>(s.answered), static_cast<unsigned long long>(s.lost),
        static_cast<unsigned long long>(s.fault_forces), p50, p99, s.force_max_N);
    if (!stats_json.empty()) {
      std::ofstream f(stats_json);
      f << "{\"sent\": " << s.sent << ", \"forces\": " << s.forces
        << ", \"answered\": " << s.answered << ", \"lost\": " << s.lost
        << ", \"fault_forces\": " << s.fault_forces << ", \"round_trip_us\": {\"p50\": " << p50
        << ", \"p99\": " << p99 << "}}\n";
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-device-example: %s\n", e.what());
    return 2;
  }
  return 0;
}
