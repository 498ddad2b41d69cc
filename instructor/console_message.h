#pragma once
// The console page's WebSocket text messages, decoded: "cue STATION KIND PARAM|off", and the
// recording and replay commands (SessionCommand). The
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

// The session controls' commands (console_session.h): "record start [NAME]", "record stop",
// "record delete FILE", "record rename FILE NAME", "replay play FILE [SPEED [FROM_S]]", "replay add
// FILE", "replay pause", "replay speed SPEED", "replay seek AT_S", "replay stop".
struct SessionCommand {
  enum class Verb {
    kRecordStart,
    kRecordStop,
    kRecordDelete,
    kRecordRename,
    kReplayPlay,
    kReplayAdd,
    kReplayPause,
    kReplaySpeed,
    kReplaySeek,
    kReplayStop
  };
  Verb verb = Verb::kRecordStop;
  std::string file;   // record start (may be ""), record delete/rename, replay play/add
  std::string name;   // record rename: the new name (NAME.db)
  double speed = 1;   // replay play, replay speed
  double from_s = 0;  // replay play (FROM_S), replay seek (AT_S)
};

// True when the message's verb is "record" or "replay".
bool IsSessionMessage(const std::string& message);
// Throws std::invalid_argument naming what is wrong (quoting at most 64 characters of it).
SessionCommand ParseSessionMessage(const std::string& message);
// A recording's file name as the controls take it: letters, digits, '.', '_', '-', at most
// 96 characters, not starting with '.', ending in ".db" (added to a NAME without it by
// `record start`). Returns "" when valid, else why not.
std::string CheckRecordingName(const std::string& name);

}  // namespace microdex::instructor
