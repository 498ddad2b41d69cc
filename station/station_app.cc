#include "station/station_app.h"

#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <thread>
#include <vector>

#include "common/base/json_text.h"
#include "common/scene/scene.h"
#include "common/state/state_hash.h"
#include "station/audio_out.h"
#include "station/dds_device.h"
#include "station/haptic_loop.h"
#include "station/module.h"
#include "station/page_device.h"
#include "station/playback_device.h"
#include "station/rt/clock.h"
#include "station/rt/realtime.h"
#include "station/sim_trainee.h"
#include "station/station_publisher.h"
#include "station/station_view.h"

namespace microdex::station {
namespace {

constexpr int kHapticPriority = 80;
constexpr int kPublisherPriority = 40;

std::string StateHashHex(std::uint64_t h) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

void WriteScoreJson(const std::string& path, const StationOptions& o, const std::string& session,
                    const scene::SceneModel& scene, const StationPublisher& pub,
                    const HapticLoop& loop, bool realtime) {
  const net::Score s = pub.final_score();
  const PeriodStats& p = pub.run_periods();
  const PublisherTotals& t = pub.totals();
  std::ofstream f(path);
  if (!f) throw std::runtime_error("score-out '" + path + "': cannot write");
  f << "{\n";
  f << "  \"station_id\": " << JsonString(s.header.station_id) << ",\n";
  f << "  \"session_id\": " << JsonString(session) << ",\n";
  f << "  \"scene\": " << JsonString(scene.path) << ",\n";
  f << "  \"skill\": " << JsonNumber(o.skill) << ",\n";
  f << "  \"seed\": " << o.seed << ",\n";
  f << "  \"steps\": " << loop.step() << ",\n";
  f << "  \"duration_s\": " << JsonNumber(s.duration_s) << ",\n";
  f << "  \"time_in_contact_s\": " << JsonNumber(s.time_in_contact_s) << ",\n";
  f << "  \"contacts\": " << s.contacts << ",\n";
  f << "  \"mean_clearance_m\": " << JsonNumber(s.mean_clearance_m) << ",\n";
  f << "  \"min_clearance_m\": " << JsonNumber(s.min_clearance_m) << ",\n";
  f << "  \"path_length_m\": " << JsonNumber(s.path_length_m) << ",\n";
  f << "  \"ideal_path_length_m\": " << JsonNumber(s.ideal_path_length_m) << ",\n";
  f << "  \"tremor_rms_m\": " << JsonNumber(s.tremor_rms_m) << ",\n";
  f << "  \"score\": " << JsonNumber(s.score) << ",\n";
  f << "  \"task\": " << JsonString(s.task) << ",\n";
  f << "  \"outcome\": "
    << JsonString(s.outcome == 1 ? "completed" : (s.outcome == 2 ? "time_limit" : "running"))
    << ",\n";
  f << "  \"progress\": " << JsonNumber(s.progress) << ",\n";
  f << "  \"deviation_mean_m\": " << JsonNumber(s.deviation_mean_m) << ",\n";
  f << "  \"terms\": [";
  for (std::size_t i = 0; i < s.terms.size(); ++i) {
    const net::ScoreTerm& term = s.terms[i];
    f << (i ? ", " : "") << "{\"metric\": " << JsonString(term.metric)
      << ", \"value\": " << JsonNumber(term.value) << ", \"limit\": " << JsonNumber(term.limit)
      << ", \"weight\": " << JsonNumber(term.weight) << ", \"points\": " << JsonNumber(term.points)
      << "}";
  }
  f << "],\n";
  f << "  \"loop\": {\"ticks\": " << t.snapshots
    << ", \"period_mean_ms\": " << JsonNumber(p.mean_s() * 1e3)
    << ", \"period_p99_ms\": " << JsonNumber(p.Quantile_s(0.99) * 1e3)
    << ", \"period_p999_ms\": " << JsonNumber(p.Quantile_s(0.999) * 1e3)
    << ", \"period_max_ms\": " << JsonNumber(p.max_s() * 1e3) << ", \"overruns\": " << t.overruns
    << ", \"ring_dropped\": " << loop.ring_dropped()
    << ", \"input_published\": " << t.input_published
    << ", \"input_write_failed\": " << t.input_write_failed
    << ", \"realtime\": " << (realtime ? "true" : "false") << "},\n";
  // The period in windows of PeriodWindow::kTicks ticks, as parallel arrays.
  const std::vector<PeriodWindow>& windows = pub.period_windows();
  const auto write_array = [&](const char* key, const auto& value) {
    f << "  \"" << key << "\": [";
    for (std::size_t i = 0; i < windows.size(); ++i) f << (i ? ", " : "") << value(windows[i]);
    f << "],\n";
  };
  f << "  \"window_length_ticks\": " << PeriodWindow::kTicks << ",\n";
  write_array("window_start_ns", [](const PeriodWindow& w) { return w.start_stamp_ns; });
  write_array("window_ticks", [](const PeriodWindow& w) { return w.ticks; });
  write_array("window_p99_ms", [](const PeriodWindow& w) { return JsonNumber(w.p99_s * 1e3); });
  write_array("window_max_ms", [](const PeriodWindow& w) { return JsonNumber(w.max_s * 1e3); });
  write_array("window_overruns", [](const PeriodWindow& w) { return w.overruns; });
  f << "  \"modules\": [";
  for (std::size_t i = 0; i < scene.modules.size(); ++i) {
    const PeriodStats& m = pub.run_step_times(i);
    const ModuleStatus status = loop.simulation().module(i).Status(loop.state());
    f << (i ? ", " : "") << "{\"name\": " << JsonString(scene.modules[i])
      << ", \"step_mean_us\": " << JsonNumber(m.mean_s() * 1e6)
      << ", \"step_p99_us\": " << JsonNumber(m.Quantile_s(0.99) * 1e6)
      << ", \"step_max_us\": " << JsonNumber(m.max_s() * 1e6)
      << ", \"error_kind\": " << JsonString(loop.module_error_kind(i))
      << ", \"error_estimate\": " << JsonNumber(status.error_estimate)
      << ", \"warnings\": " << status.warnings << "}";
  }
  f << "],\n";
  f << "  \"cues_applied\": [";
  for (std::size_t i = 0; i < t.cues_applied.size(); ++i) {
    const AppliedCue& a = t.cues_applied[i];
    f << (i ? ", " : "") << "{\"cue_id\": " << a.cue.cue_id
      << ", \"kind\": " << JsonString(cues::CueKindName(a.cue.kind))
      << ", \"param\": " << JsonNumber(a.cue.param)
      << ", \"off\": " << (a.cue.off ? "true" : "false") << ", \"step\": " << a.step << "}";
  }
  f << "],\n  \"cues_rejected\": " << t.cues_rejected << ",\n";
  f << "  \"cues_invalid\": " << t.cues_invalid << ",\n";
  f << "  \"state_hash\": \"" << StateHashHex(state::CalcStateHash(loop.state())) << "\",\n";
  f << "  \"state_hash_version\": " << state::kStateHashVersion << "\n}\n";
}

// Starts node on station/page/screenshot.mjs against this station's view; -1 when it cannot.
pid_t StartScreenshot(std::uint16_t port, const std::string& out) {
  const std::string script = std::string(MICRODEX_SOURCE_DIR) + "/station/page/screenshot.mjs";
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  std::vector<std::string> args = {"node", script, "--url", url, "--out", out};
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawnp(&pid, "node", nullptr, nullptr, argv.data(), environ) != 0) {
    spdlog::error("--screenshot: cannot run node");
    return -1;
  }
  return pid;
}

// A DDS device's mapping: the hand's motion scaled for the scene's microscope (1 / its
// magnification), the device's origin at `p_W_centre`, the force limited at the scene's limit;
// then whatever --device-map FILE says for this device (0 first, 1 second).
DeviceMappingDef DdsDeviceMapping(const scene::SceneModel& scene, const std::string& file,
                                  int device, const Eigen::Vector3d& p_W_centre) {
  DeviceMappingDef d;
  d.motion_scale = 1.0 / scene.microscope.magnification;
  d.max_force_N = scene.haptic.max_force_N;
  if (!file.empty()) d = LoadDeviceMapping(file, device, d);
  d.p_W_centre = p_W_centre;
  return d;
}

}  // namespace

std::string StationOptions::Validate() const {
  if (scene_path.empty()) return "--scene: required";
  if (!(spin_us >= 0 && spin_us <= 500)) {
    return "--spin-us: expected 0..500 µs (got " + std::to_string(spin_us) + ")";
  }
  if (device == "playback") {
    if (device_file.empty()) return "--device playback: expected a FILE (CSV)";
  } else if (device == "dds") {
    if (unpaced) return "--unpaced: not with --device dds (the driver paces the loop)";
  } else if (device == "gui") {
    return "--device gui: not available in this build (sim, page, playback, dds)";
  } else if (device != "sim" && device != "page") {
    return "--device: expected sim|page|playback FILE|dds";
  }
  if (device != "playback" && !device_file.empty()) {
    return "--device " + device + ": takes no FILE";
  }
  if (device != "playback" && !device_file2.empty()) {
    return "--device " + device + ": takes no FILE2";
  }
  if (!device_map.empty() && device != "dds") return "--device-map: only with --device dds";
  if (!(view_port >= -1 && view_port <= 65535)) return "--view: expected a port 0..65535";
  if (device == "page" && view_port < 0 && screenshot.empty()) {
    return "--device page: needs --view PORT";
  }
  if (!screenshot.empty() && (screenshot.size() < 5 || !screenshot.ends_with(".png"))) {
    return "--screenshot: expected a FILE.png";
  }
  if (device == "page" && unpaced) return "--device page: cannot run --unpaced";
  if (!(skill >= 0 && skill <= 1)) return "--skill: expected 0..1";
  if (!(duration_s >= 0) || !std::isfinite(duration_s)) return "--duration: expected >= 0 s";
  if (station_id.empty() || station_id.size() > 64) return "--station-id: expected 1..64 chars";
  if (station_id == "all") return "--station-id: 'all' is reserved for cues to every station";
  if (trainee.size() > 128) return "--trainee: longer than 128 characters";
  if (!(mirror_rate_hz >= 1 && mirror_rate_hz <= 1000)) return "--mirror-rate: expected 1..1000 Hz";
  for (const std::string& c : cues) {
    try {
      cues::ParseCueArg(c);
    } catch (const std::invalid_argument& e) {
      return std::string("--cue ") + e.what();
    }
  }
  if (cues.size() > 16) return "--cue: at most 16";
  if (!(wait_for_recorder_s >= 0 && wait_for_recorder_s <= 600)) {
    return "--wait-for-recorder: expected 0..600 s";
  }
  if (!(wait_for_condition_s >= 0 && wait_for_condition_s <= 600)) {
    return "--wait-for-condition: expected 0..600 s";
  }
  if (std::string why = dds.Validate(); !why.empty()) return "--" + why;
  return {};
}

int RunStation(const StationOptions& o, const std::atomic<bool>& stop) {
  const scene::SceneModel scene = scene::LoadScene(o.scene_path);
  SimTraineeDef trainee_def;
  trainee_def.skill = o.skill;
  trainee_def.seed = o.seed;
  trainee_def.Validate();
  const std::string session_id = o.station_id + "-" +
                                 std::to_string(rt::MonotonicClock().RealtimeNs() / 1'000'000) +
                                 "-" + std::to_string(getpid());
  std::unique_ptr<Device> device_owner;
  PageDevice* page_device = nullptr;
  std::vector<const DdsDevice*> bridges;  // --device dds: its samples refused (Telemetry)
  if (o.device == "page") {
    auto page = std::make_unique<PageDevice>(scene.CalcIdealToolPose(0));
    page_device = page.get();
    device_owner = std::move(page);
  } else if (o.device == "playback") {
    device_owner = std::make_unique<PlaybackDevice>(o.device_file);
  } else if (o.device == "dds") {
    // The driver's hand at the device origin puts the tool at the task's start.
    const DeviceMappingDef mapping =
        DdsDeviceMapping(scene, o.device_map, 0, scene.CalcIdealToolPose(0).translation());
    auto bridge = std::make_unique<DdsDevice>(o.dds, o.station_id, session_id.substr(0, 64),
                                              mapping, DeviceGuardDef{}, o.device_bridge_tuning);
    spdlog::info(
        "device bridge: participant '{}', {} DDS threads SCHED_FIFO {}, CPU latency request {} "
        "(tuning {})",
        bridge->participant_profile(), bridge->dds_threads_realtime(),
        DdsDevice::kDdsThreadPriority, bridge->cpu_latency_held() ? "held" : "not held",
        o.device_bridge_tuning.Name());
    bridges.push_back(bridge.get());
    device_owner = std::move(bridge);
  } else {
    device_owner = std::make_unique<SimTrainee>(scene, trainee_def);
  }
  Device& device = *device_owner;
  // A bimanual scene: the second tool's device, of the same kind as the first.
  std::unique_ptr<Device> second_device;
  if (scene.hands() == 2) {
    const Eigen::Isometry3d X_WT2_start = scene.CalcIdealSecondToolPose(0);
    if (o.device == "page") {
      second_device = std::make_unique<HeldDevice>(X_WT2_start);
    } else if (o.device == "playback") {
      if (o.device_file2.empty()) {
        throw std::runtime_error(scene.path + ": the trainee holds two tools: --device playback " +
                                 "FILE FILE2 (FILE2: the second tool's CSV)");
      }
      second_device = std::make_unique<PlaybackDevice>(o.device_file2);
    } else if (o.device == "dds") {
      // The second device's driver publishes and reads under the key STATION/2.
      const DeviceMappingDef mapping =
          DdsDeviceMapping(scene, o.device_map, 1, X_WT2_start.translation());
      auto bridge = std::make_unique<DdsDevice>(o.dds, SecondDeviceKey(o.station_id),
                                                session_id.substr(0, 64), mapping, DeviceGuardDef{},
                                                o.device_bridge_tuning);
      bridges.push_back(bridge.get());
      second_device = std::move(bridge);
    } else {
      SimTraineeDef other_hand = trainee_def;
      other_hand.hand = 1;
      second_device = std::make_unique<SimTrainee>(scene, other_hand);
    }
  } else if (!o.device_file2.empty()) {
    throw std::runtime_error(scene.path + ": the trainee holds one tool: --device playback " +
                             "takes one FILE");
  }

  bool realtime = false;
  if (o.realtime) {
    std::string why;
    realtime = rt::LockMemory(&why);
    if (!realtime) spdlog::warn("not real-time: {} (the loop keeps absolute deadlines)", why);
  } else {
    spdlog::info("real-time scheduling disabled by option");
  }

  StationRings rings;
  // Paced: absolute 1 kHz deadlines on the monotonic clock. Unpaced: a clock that jumps to each
  // deadline, so the loop runs as fast as it can in simulated time.
  rt::MonotonicClock wall_clock(static_cast<std::int64_t>(o.spin_us * 1e3));
  rt::ManualClock unpaced_clock(wall_clock.NowNs());
  rt::Clock& clock = o.unpaced ? static_cast<rt::Clock&>(unpaced_clock) : wall_clock;
  // The modules write their large frames once per mirror period.
  const int frame_period_steps =
      static_cast<int>(std::max(1L, std::lround(scene.haptic.rate_hz / o.mirror_rate_hz)));
  HapticLoopConfig lc;
  lc.seed = o.seed;
  lc.frame_period_steps = frame_period_steps;
  lc.wait_for_ring = o.unpaced;
  // A trainee at a device or at the page goes on after the task ends (the scores freeze); a
  // simulated one and a playback stop there.
  lc.stop_at_task_end = o.device != "dds" && page_device == nullptr;
  HapticLoop loop(scene, device, rings, clock, lc, second_device.get());
  // --cue: from the first step, through the ring the instructor's cues take (the threads
  // start below, so this thread may stand in for the producer).
  for (const std::string& text : o.cues) {
    const cues::CueArg a = cues::ParseCueArg(text);
    if (!rings.cues.TryPush({0, a.kind, a.param, 0, a.off})) {
      throw std::runtime_error("--cue: too many cues");
    }
  }
  std::unique_ptr<AudioOut> audio;
  if (!o.audio_out.empty()) audio = std::make_unique<AudioOut>(scene.haptic.rate_hz);

  PublisherConfig pc;
  pc.station_id = o.station_id;
  pc.session_id = session_id.substr(0, 64);
  pc.trainee = o.trainee;
  pc.device = o.device;
  pc.skill = o.skill;
  pc.seed = o.seed;
  // A recorded station (--wait-for-recorder) leaves only once the recorder has every step.
  if (o.wait_for_recorder_s > 0) pc.input_ack_wait_s = std::max(2.0, o.wait_for_recorder_s);
  pc.mirror_rate_hz = o.mirror_rate_hz;
  if (!bridges.empty()) {
    pc.device_samples_invalid = [bridges] {
      std::uint64_t n = 0;
      for (const DdsDevice* b : bridges) n += b->samples_invalid();
      return n;
    };
  }
  // The page's audio (--view): blocks of the audio cues for the pages that ask for them.
  std::unique_ptr<StationView> view;
  std::unique_ptr<AudioBlockStream> live_audio;
  if (o.view_port >= 0 || !o.screenshot.empty()) {
    view = std::make_unique<StationView>(scene, std::max(o.view_port, 0),
                                         o.web_dir.empty() ? DefaultWebDir() : o.web_dir,
                                         o.station_id, page_device);
    live_audio = std::make_unique<AudioBlockStream>(
        scene.haptic.rate_hz,
        [v = view.get()](const view::AudioBlock& b) { return v->PushAudio(b); });
  }
  if (audio || live_audio) {
    pc.on_snapshot = [&audio, &live_audio, &view](const TickSnapshot& s) {
      if (audio) audio->Add(s);
      if (live_audio) live_audio->Add(s, view->audio_wanted());
    };
  }
  StationPublisher publisher(pc, o.dds, scene, rings, loop);
  if (view) {
    publisher.SetViewFrames(&view->frames());
    // One line a script can wait for (the port is the bound one when --view 0).
    spdlog::info("view: http://127.0.0.1:{}/", view->port());
  }

  if (o.wait_for_recorder_s > 0) {
    std::string missing;
    if (!publisher.WaitForRecorder(o.wait_for_recorder_s, stop, &missing)) {
      spdlog::warn("no reader of {} after {} s: starting, not every sample recorded", missing,
                   o.wait_for_recorder_s);
    }
  }
  // --wait-for-condition: the trial's cues (in the cue ring now) apply at the first step.
  if (o.wait_for_condition_s > 0) {
    std::string why;
    if (!publisher.WaitForCondition(o.wait_for_condition_s, stop, &why)) {
      throw std::runtime_error(why);
    }
  }

  const auto max_steps =
      o.duration_s > 0
          ? static_cast<std::uint64_t>(std::llround(o.duration_s * scene.haptic.rate_hz))
          : UINT64_MAX;
  std::atomic<bool> haptic_stop{false};
  std::atomic<bool> haptic_done{false};
  std::atomic<bool> fifo{false};
  std::string fifo_why;
  std::thread haptic([&] {
    if (o.realtime && !o.unpaced) fifo = rt::MakeThisThreadFifo(kHapticPriority, &fifo_why);
    loop.Run(haptic_stop, max_steps);
    haptic_done = true;
  });
  // The publisher thread gets a lower real-time priority than the haptic thread: it sleeps
  // on its WaitSet almost always, and waking promptly after each tick keeps the age of the
  // published state small on a loaded machine.
  std::thread pub_thread([&] {
    if (o.realtime && !o.unpaced) {
      std::string why;
      if (!rt::MakeThisThreadFifo(kPublisherPriority, &why)) {
        spdlog::warn("publisher thread not SCHED_FIFO: {}", why);
      }
    }
    publisher.Run();
  });

  pid_t shot = -1;
  if (!o.screenshot.empty()) shot = StartScreenshot(view->port(), o.screenshot);
  int shot_status = 0;
  while (!stop.load() && !haptic_done.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (shot > 0) {
      int status = 0;
      if (waitpid(shot, &status, WNOHANG) == shot) {
        shot = -1;
        shot_status = WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 2;
        break;
      }
    }
  }
  if (shot > 0) {  // the station ended first: the page is gone, so is the picture
    kill(shot, SIGTERM);
    waitpid(shot, nullptr, 0);
    shot_status = 2;
  }
  haptic_stop = true;
  haptic.join();
  publisher.RequestStop();
  pub_thread.join();
  if (live_audio && live_audio->blocks() > 0) {
    spdlog::info("view audio: {} blocks, {} dropped at the ring, {} dropped for slow pages",
                 live_audio->blocks(), live_audio->dropped(), view->audio_dropped());
  }
  view.reset();
  if (o.realtime && !o.unpaced && !fifo) {
    spdlog::warn("haptic thread not SCHED_FIFO: {}", fifo_why);
  }
  const bool rt_ok = realtime && fifo;
  spdlog::info("station {}: {} steps, score {:.1f}, period p99 {:.3f} ms, overruns {}, dropped {}",
               o.station_id, loop.step(), publisher.final_score().score,
               publisher.run_periods().Quantile_s(0.99) * 1e3, publisher.totals().overruns,
               loop.ring_dropped());
  if (!o.score_out.empty()) {
    WriteScoreJson(o.score_out, o, pc.session_id, scene, publisher, loop, rt_ok);
  }
  if (audio) audio->Write(o.audio_out);
  if (shot_status != 0) {
    std::fprintf(stderr, "microdex-station: --screenshot %s: not written (see above)\n",
                 o.screenshot.c_str());
  }
  return shot_status;
}

}  // namespace microdex::station
