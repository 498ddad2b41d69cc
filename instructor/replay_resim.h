#pragma once
// Re-simulation of a recorded session: each station run (station id and its session) is
// stepped again from its scene and seed with the recorded device samples (one DeviceInput per
// step) and the recorded cue acknowledgements (each cue at the step it was applied at), and
// the state hash after every step is compared with the one the station published in that
// step's DeviceInput (and, once a second, in its Telemetry).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/record/session_reader.h"

namespace microdex::instructor {

struct ResimOptions {
  // Where to look for a scene whose recorded path does not exist as given (its file name is
  // tried in this folder).
  std::string scene_dir;
  // Progress: (station, steps done, steps in all), called every few thousand steps.
  std::function<void(const std::string&, std::uint64_t, std::uint64_t)> progress;
};

struct ResimResult {
  std::string station;
  std::string session;
  std::string scene;
  std::uint64_t seed = 0;
  std::uint64_t steps = 0;              // steps re-simulated
  std::uint64_t hashes_checked = 0;     // DeviceInput hashes compared
  std::uint64_t telemetry_checked = 0;  // Telemetry hashes compared
  bool diverged = false;
  std::uint64_t divergent_step = 0;  // the first step whose hash differs
  std::uint64_t recorded_hash = 0;
  std::uint64_t resimulated_hash = 0;
  std::string problem;  // why it could not be (fully) re-simulated; "" if none
};

// Re-simulates every station run in the recording. Never throws for bad recorded data: what
// is wrong goes into the result's `problem` (or reader.problems()).
std::vector<ResimResult> Resimulate(record::SessionReader& reader, const ResimOptions& options);

// One line for a result: "station S: N steps, all hashes match" or the divergence.
std::string FormatResimResult(const ResimResult& r);

}  // namespace microdex::instructor
