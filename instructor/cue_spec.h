#pragma once
// The --cue STATION:KIND:PARAM[@SECONDS] argument of microdex-instructor: switch cue KIND (any
// of common/cues/cue_kind.h: clear, convergent, divergent, amplified_tremor, visual_*, audio_*,
// wall, predictive) on with PARAM, or off with PARAM 'off', at STATION (or "all"), SECONDS
// after the start (default 0).

#include <string>

#include "common/net/messages.h"

namespace microdex::instructor {

struct CueSpec {
  std::string station;
  cues::CueKind kind = cues::CueKind::kClear;
  double param = 0;
  bool off = false;
  double at_s = 0;
};

// Throws std::invalid_argument naming what is wrong with `text` (a kind that does not exist,
// a parameter that is not a number or is out of the kind's limits).
CueSpec ParseCueSpec(const std::string& text);

}  // namespace microdex::instructor
