#pragma once
// The --cue STATION:KIND:PARAM[@SECONDS] argument of microdex-instructor: send cue KIND
// (clear, convergent, divergent, tremor) with PARAM to STATION (or "all"), SECONDS after the
// start (default 0).

#include <string>

#include "common/net/messages.h"

namespace microdex::instructor {

struct CueSpec {
  std::string station;
  cues::CueKind kind = cues::CueKind::kClear;
  double param = 0;
  double at_s = 0;
};

// Throws std::invalid_argument naming what is wrong with `text`.
CueSpec ParseCueSpec(const std::string& text);

}  // namespace microdex::instructor
