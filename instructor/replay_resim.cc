#include "instructor/replay_resim.h"

#include <cstdio>
#include <map>

#include "common/record/recorded_topics.h"
#include "common/scene/scene.h"
#include "common/state/state_hash.h"
#include "device_inputPubSubTypes.h"
#include "instructor/recorded_sample.h"
#include "instructor/replay_player.h"
#include "station/station_step.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"

namespace microdex::instructor {
namespace {

using record::TopicIndex;

int Index(TopicIndex t) { return static_cast<int>(t); }

struct Run {
  std::string station, session;
  bool have_info = false;
  std::string scene;
  std::uint64_t seed = 0;
  std::uint64_t inputs = 0;
  std::map<std::uint64_t, std::vector<state::CueRequest>> cues_at_step;
  std::map<std::uint64_t, std::uint64_t> telemetry_hash;  // step → hash
};

std::string Hex(std::uint64_t h) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// Collects the runs: StationInfo (scene, seed), cue acknowledgements, telemetry hashes, and
// the number of device samples, by (station, session).
std::map<std::pair<std::string, std::string>, Run> CollectRuns(record::SessionReader& reader) {
  std::map<std::pair<std::string, std::string>, Run> runs;
  auto run_for = [&](std::string_view station, std::string_view session) -> Run& {
    Run& r = runs[{std::string(station), std::string(session)}];
    r.station = station;
    r.session = session;
    return r;
  };
  msg::DeviceInput input;
  reader.ForEach({Index(TopicIndex::kDeviceInput)}, [&](const record::MessageView& m) {
    ++run_for(m.station, m.session).inputs;
    return true;
  });
  msg::StationInfo info;
  reader.ForEach({Index(TopicIndex::kStationInfo)}, [&](const record::MessageView& m) {
    if (!DecodeSample<msg::StationInfoPubSubType>(m.cdr, info)) return true;
    Run& r = run_for(m.station, m.session);
    r.have_info = true;
    r.scene = info.scene().to_string();
    r.seed = info.seed();
    return true;
  });
  msg::TaskEvent event;
  reader.ForEach({Index(TopicIndex::kTaskEvent)}, [&](const record::MessageView& m) {
    if (!DecodeSample<msg::TaskEventPubSubType>(m.cdr, event)) return true;
    if (event.kind() != msg::EVENT_CUE_APPLIED) return true;
    // The acknowledgement names the kind, and " off" when the cue was switched off.
    std::string text = event.text().to_string();
    const bool off = text.size() > 4 && text.compare(text.size() - 4, 4, " off") == 0;
    if (off) text.resize(text.size() - 4);
    cues::CueKind kind{};
    if (!cues::ParseCueKind(text, &kind)) return true;
    run_for(m.station, m.session)
        .cues_at_step[event.step()]
        .push_back({event.cue_id(), kind, event.value(), event.step(), off});
    return true;
  });
  msg::Telemetry tel;
  reader.ForEach({Index(TopicIndex::kTelemetry)}, [&](const record::MessageView& m) {
    if (!DecodeSample<msg::TelemetryPubSubType>(m.cdr, tel) || tel.has_state_hash() == 0) {
      return true;
    }
    run_for(m.station, m.session).telemetry_hash[tel.state_hash_step()] = tel.state_hash();
    return true;
  });
  return runs;
}

void ResimulateRun(record::SessionReader& reader, const Run& run, const ResimOptions& options,
                   ResimResult& out) {
  if (!run.have_info) {
    out.problem = "no StationInfo recorded (scene and seed unknown)";
    return;
  }
  if (run.inputs == 0) {
    out.problem = "no DeviceInput recorded";
    return;
  }
  const std::string scene_path = FindRecordedScene(run.scene, options.scene_dir);
  if (scene_path.empty()) {
    out.problem = "scene '" + run.scene + "': not found (give its folder with --scene-dir)";
    return;
  }
  scene::SceneModel scene;
  try {
    scene = scene::LoadScene(scene_path);
  } catch (const std::exception& e) {
    out.problem = std::string("scene: ") + e.what();
    return;
  }
  std::unique_ptr<station::Simulation> sim;
  try {
    sim = std::make_unique<station::Simulation>(scene);
  } catch (const std::exception& e) {
    out.problem = std::string("scene: ") + e.what();
    return;
  }
  state::StationState state = sim->MakeInitialState(run.seed);
  msg::DeviceInput m;
  std::string why;
  reader.ForEach({Index(TopicIndex::kDeviceInput), run.station}, [&](const record::MessageView& v) {
    if (v.session != run.session) return true;
    if (!DecodeSample<msg::DeviceInputPubSubType>(v.cdr, m, &why)) {
      out.problem = "DeviceInput at step " + std::to_string(v.step) + ": " + why;
      return false;
    }
    if (m.step() < state.step) return true;  // delivered twice
    if (m.step() > state.step) {
      const std::string missing =
          m.step() == state.step + 1
              ? "step " + std::to_string(state.step)
              : "steps " + std::to_string(state.step) + ".." + std::to_string(m.step() - 1);
      out.problem = "DeviceInput of " + missing + " not recorded: re-simulated up to step " +
                    std::to_string(state.step) + " only (start its station with " +
                    "--wait-for-recorder)";
      return false;
    }
    station::StationInput in;
    const auto& p = m.p_WT();
    const auto& q = m.q_WT();
    in.device = station::DeviceSampleFromRecord(Eigen::Vector3d(p[0], p[1], p[2]),
                                                Eigen::Quaterniond(q[0], q[1], q[2], q[3]),
                                                m.gripper(), m.buttons());
    const auto& p2 = m.p_WT2();
    const auto& q2 = m.q_WT2();
    in.second = station::DeviceSampleFromRecord(Eigen::Vector3d(p2[0], p2[1], p2[2]),
                                                Eigen::Quaterniond(q2[0], q2[1], q2[2], q2[3]),
                                                m.gripper2(), m.buttons2());
    const auto cues = run.cues_at_step.find(state.step);
    if (cues != run.cues_at_step.end()) in.cues = cues->second;
    const std::uint64_t step = state.step;
    station::StepStation(*sim, in, state);
    ++out.steps;
    const std::uint64_t h = state::CalcStateHash(state);
    ++out.hashes_checked;
    if (h != m.state_hash()) {
      out.diverged = true;
      out.divergent_step = step;
      out.recorded_hash = m.state_hash();
      out.resimulated_hash = h;
      return false;
    }
    const auto t = run.telemetry_hash.find(step);
    if (t != run.telemetry_hash.end()) {
      ++out.telemetry_checked;
      if (t->second != h) {
        out.diverged = true;
        out.divergent_step = step;
        out.recorded_hash = t->second;
        out.resimulated_hash = h;
        return false;
      }
    }
    if (options.progress && out.steps % 5000 == 0) {
      options.progress(run.station, out.steps, run.inputs);
    }
    return true;
  });
}

}  // namespace

std::vector<ResimResult> Resimulate(record::SessionReader& reader, const ResimOptions& options) {
  std::vector<ResimResult> results;
  for (const auto& [key, run] : CollectRuns(reader)) {
    ResimResult r;
    r.station = run.station;
    r.session = run.session;
    r.scene = run.scene;
    r.seed = run.seed;
    if (run.inputs == 0 && !run.have_info) continue;  // a cue target such as "all"
    ResimulateRun(reader, run, options, r);
    results.push_back(std::move(r));
  }
  return results;
}

std::string FormatResimResult(const ResimResult& r) {
  std::string s = "station " + r.station + " (session " + r.session + ", scene " + r.scene +
                  ", seed " + std::to_string(r.seed) + "): ";
  if (r.diverged) {
    return s + "DIVERGES at step " + std::to_string(r.divergent_step) + " (recorded hash " +
           Hex(r.recorded_hash) + ", re-simulated " + Hex(r.resimulated_hash) + ")";
  }
  s += std::to_string(r.steps) + " steps re-simulated, " + std::to_string(r.hashes_checked) +
       " step hashes and " + std::to_string(r.telemetry_checked) + " telemetry hashes match";
  if (!r.problem.empty()) s += "; " + r.problem;
  return s;
}

}  // namespace microdex::instructor
