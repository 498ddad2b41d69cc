// microdex-station: one trainee station (README.md "Command-line contracts").
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>

#include "common/cues/cue_kind.h"
#include "common/net/app_cli.h"
#include "station/station_app.h"

namespace {

std::atomic<bool> g_stop{false};

}  // namespace

// Errors are caught around parsing and the run; what could escape is an allocation failure
// while setting up, which ends the process as it should.
int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  const microdex::net::StopSignals stop_signals;

  microdex::station::StationOptions o;
  o.station_id = "station-" + std::to_string(getpid());
  o.dds.profile_file = microdex::net::DefaultDdsProfileFile();
  o.dds.participant_name = "microdex-station";
  bool window = false;
  bool no_realtime = false;

  CLI::App app{"microdex-station: one trainee station (haptic loop, physics modules, DDS)"};
  app.add_option("--scene", o.scene_path, "scene file (YAML)")->required();
  std::vector<std::string> device_args;
  app.add_option("--device", device_args,
                 "input device: sim (simulated trainee), page (the view page's keyboard and mouse; "
                 "needs --view), playback FILE [FILE2] (a recorded CSV; FILE2 the second tool's "
                 "in a bimanual scene), dds (an external driver over the DDS device bridge)")
      ->expected(1, 3);
  app.add_option("--skill", o.skill, "simulated trainee skill, 0 novice .. 1 expert");
  app.add_option("--seed", o.seed, "seed of the simulated trainee");
  app.add_option("--duration", o.duration_s, "stop after S seconds (0: until SIGINT/SIGTERM)");
  app.add_option("--station-id", o.station_id, "station id (DDS key)");
  app.add_option("--trainee", o.trainee, "trainee name shown to the instructor");
  app.add_option("--score-out", o.score_out, "write the final score as JSON to FILE");
  app.add_option("--mirror-rate", o.mirror_rate_hz, "rate of the mirrored state topics, Hz");
  app.add_option("--view", o.view_port,
                 "serve the microscope view on http://127.0.0.1:PORT/ (0: any free port)");
  app.add_option("--cue", o.cues,
                 std::string("KIND[:PARAM|:off], repeatable: a cue on from the first step; KIND "
                             "one of ") +
                     microdex::cues::CueKindNames());
  app.add_option("--audio-out", o.audio_out, "render the audio cues that are on to FILE.wav");
  app.add_option("--device-map", o.device_map,
                 "--device dds: workspace mapping, scaling and limits of the device(s) (YAML)");
  app.add_option("--wait-for-recorder", o.wait_for_recorder_s,
                 "before the first step, wait up to S seconds for a DeviceInput reader (a "
                 "recording instructor) and for a reader of each of its topics, so that the "
                 "recording holds every sample from the first");
  app.add_option("--wait-for-condition", o.wait_for_condition_s,
                 "before the first step, wait up to S seconds for this run's condition from the "
                 "instructor's experiment (its cue commands, applied from step 0); none by "
                 "then: exit 2 naming the station and the instructor");
  microdex::net::AddDdsOptions(app, o.dds);
  std::string bridge_tuning = "all";
  app.add_option("--device-bridge-tuning", bridge_tuning,
                 "--device dds: all (default), none, or a comma list of shm (shared-memory "
                 "participant profile), rt (the bridge's DDS threads SCHED_FIFO), cpu (a 0 us "
                 "PM QoS CPU latency request while running; --no-realtime: rt and cpu off)");
  app.add_option("--spin-us", o.spin_us,
                 "the haptic loop sleeps until this many µs before each deadline and polls the "
                 "clock for the rest (0: sleeps to the deadline; 0..500)");
  app.add_flag("--no-realtime", no_realtime, "do not try SCHED_FIFO and mlockall");
  app.add_flag("--unpaced", o.unpaced,
               "step as fast as possible in simulated time (same results as paced)");
  app.add_flag("--window", window, "open a view window (not available in this build)");
  app.add_option("--screenshot", o.screenshot,
                 "render the view page headless to FILE.png once it has drawn, then stop");
  microdex::net::AddSecurityOption(app, o.dds);
  if (const std::optional<int> status =
          microdex::net::ParseCommandLine(app, argc, argv, "microdex-station")) {
    return *status;
  }
  if (window) {
    std::fprintf(stderr, "microdex-station: --window: not available in this build yet\n");
    return 2;
  }
  o.dds.security_station = o.station_id;  // with --security: its partition COURSE/ID
  if (const std::string why = microdex::net::CheckSecurityOption(o.dds); !why.empty()) {
    std::fprintf(stderr, "microdex-station: %s\n", why.c_str());
    return 2;
  }
  o.realtime = !no_realtime;
  if (const std::string why =
          microdex::station::DdsBridgeTuning::Parse(bridge_tuning, &o.device_bridge_tuning);
      !why.empty()) {
    std::fprintf(stderr, "microdex-station: --device-bridge-tuning %s\n", why.c_str());
    return 2;
  }
  // Without real-time scheduling the bridge's threads stay at normal priority as well.
  if (no_realtime) {
    o.device_bridge_tuning.realtime_threads = false;
    o.device_bridge_tuning.cpu_latency = false;
  }
  if (!device_args.empty()) o.device = device_args[0];
  if (device_args.size() > 1) o.device_file = device_args[1];
  if (device_args.size() > 2) o.device_file2 = device_args[2];
  if (std::string why = o.Validate(); !why.empty()) {
    std::fprintf(stderr, "microdex-station: %s\n", why.c_str());
    return 2;
  }
  spdlog::set_pattern("[%H:%M:%S.%e] [station] [%l] %v");

  stop_signals.Watch(g_stop);
  try {
    return microdex::station::RunStation(o, g_stop);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-station: %s\n", e.what());
    return 2;
  }
}
