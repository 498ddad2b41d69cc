#pragma once
// microdex-station as a library: options, validation and the run, so that tests and the
// benchmark can start a station in-process as well as through the binary.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "common/net/dds_context.h"
#include "station/dds_bridge_tuning.h"

namespace microdex::station {

struct StationOptions {
  std::string scene_path;
  std::string device = "sim";  // sim | playback (device_file) | dds
  std::string device_file;     // --device playback FILE: the CSV (station/playback_device.h)
  // --device playback FILE FILE2: the second tool's CSV (bimanual scenes).
  std::string device_file2;
  std::string device_map;  // --device-map FILE.yaml: the dds devices' mapping ("" defaults)
  double skill = 0.5;
  std::uint64_t seed = 1;
  double duration_s = 0;   // 0: until SIGINT/SIGTERM
  std::string station_id;  // default: station-<pid>
  std::string trainee = "simulated trainee";
  std::string score_out;  // JSON file written at the end ("" none)
  double mirror_rate_hz = 60;
  bool realtime = true;  // try SCHED_FIFO + mlockall
  // The haptic loop's pacing: it sleeps until this long before each deadline, then polls the
  // clock until it (rt/clock.h): a halted core's wake-up is paid before the deadline.
  // 0: sleep to the deadline. Not with --unpaced.
  double spin_us = 0;
  // --cue KIND[:PARAM|:off]: cues switched on (off) at the first step, as the instructor's
  // command would (common/cues/cue_kind.h).
  std::vector<std::string> cues;
  std::string audio_out;  // --audio-out FILE.wav: the audio cues rendered ("" none)
  // Step as fast as the machine allows, without the 1 kHz pacing (reports, tests): the same
  // scene, skill, seed and duration (in simulated seconds) give the same steps, score and state
  // hash as a paced run. Not real time: the haptic thread may wait for the publisher.
  bool unpaced = false;
  // Before the first step, wait up to this long for a DeviceInput reader to match (a recording
  // instructor): DeviceInput is volatile, so steps taken before it matched are not recorded.
  double wait_for_recorder_s = 0;
  // Before the first step (after the recorder), wait up to this long for the instructor's
  // condition for this run (an experiment's trial, instructor/README.md "Cue experiments"),
  // which then applies from step 0; none by then: an error naming the station and the
  // instructor. 0: do not wait.
  double wait_for_condition_s = 0;
  net::DdsOptions dds;
  // --device dds: how the bridge's participant is set up (dds_bridge_tuning.h).
  DdsBridgeTuning device_bridge_tuning;
  // The microscope view (station_view.h) on 127.0.0.1:view_port; -1: none, 0: any free port.
  int view_port = -1;
  std::string web_dir;  // the bundled pages ("" : DefaultWebDir())
  // Render the view page in headless Chromium once it has drawn a few frames, save it here
  // (PNG), then stop (station/page/screenshot.mjs; needs node and chromium).
  std::string screenshot;
  // Empty when valid; otherwise a one-line reason naming the option.
  std::string Validate() const;
};

// Runs one station until `stop` becomes true or the duration elapses. Returns the process
// exit status; throws std::runtime_error (bad scene, DDS profile...) with a one-line reason.
int RunStation(const StationOptions& options, const std::atomic<bool>& stop);

}  // namespace microdex::station
