#pragma once
// A cue experiment: a scene, cue conditions, trials per trainee, the trainees and a seed,
// read from a small YAML file (instructor/README.md, "Cue experiments"):
//
//   name: audio-pilot
//   scene: tremor_hold.yaml          # the scene file the stations run (compared by file name)
//   seed: 7
//   trials_per_trainee: 5
//   conditions:                      # name: [cue specs KIND[:PARAM|:off], as --cue]
//     none: []
//     audio: [audio_click:0.8]
//     guidance: [convergent:300]
//   trainees: [ana, ben, chloe, dan, eva, finn]
//
// and the assignment of trainees to conditions: randomised (a seeded Fisher-Yates shuffle of
// the trainee list, SplitMix64, the same on every platform) and balanced (the shuffled list
// dealt round the conditions in order, so condition sizes differ by at most one).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/cues/cue_kind.h"

namespace microdex::scores {

struct CueCondition {
  std::string name;
  std::vector<std::string> cue_specs;  // as written
  std::vector<cues::CueArg> cues;      // parsed
};

struct ExperimentDef {
  std::string file;  // where it was read from
  std::string name;
  std::string scene;
  std::uint64_t seed = 1;
  int trials_per_trainee = 1;
  std::vector<CueCondition> conditions;
  std::vector<std::string> trainees;
  // Throws std::invalid_argument("field: reason").
  void Validate() const;
};

// Reads and validates an experiment file. Throws InputError "FILE:LINE: field: reason".
ExperimentDef ReadExperiment(const std::string& path);
ExperimentDef ParseExperiment(const std::string& text, const std::string& origin);

// trainee → condition name.
std::map<std::string, std::string> AssignConditions(const ExperimentDef& e);

}  // namespace microdex::scores
