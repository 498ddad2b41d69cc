#pragma once
// The console page's WebSocket text messages, decoded: "cue STATION KIND PARAM|off". The
// decoder checks everything that needs no registry (the verb, the fields, the kind's name, a
// finite parameter within the kind's limits: cues::CheckCue); the console server then checks
// that the station exists and sends the cue.

#include <string>

#include "common/cues/cue_kind.h"

namespace microdex::instructor {

struct ConsoleCue {
  std::string station;
  cues::CueKind kind = cues::CueKind::kClear;
  double param = 0;
  bool off = false;
};

// Throws std::invalid_argument naming what is wrong (quoting at most 32 characters of it).
ConsoleCue ParseConsoleMessage(const std::string& message);

}  // namespace microdex::instructor
