#include "instructor/console_message.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "common/net/messages.h"

namespace microdex::instructor {
namespace {

std::string Num(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

// A number field of a message: finite, or the reason.
double ParseNumber(const std::string& text, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v)) {
    throw std::invalid_argument(std::string(what) + " '" + text.substr(0, 64) +
                                "' is not a number");
  }
  return v;
}

void CheckSpeed(double speed) {
  if (!(speed >= 1.0 / 64 && speed <= 1024)) {
    throw std::invalid_argument("replay: SPEED " + Num(speed) + " outside 1/64 … 1024");
  }
}

}  // namespace

ConsoleCue ParseConsoleMessage(const std::string& message) {
  std::istringstream in(message);
  std::string verb, kind_name, param_text;
  ConsoleCue cue;
  in >> verb;
  if (verb != "cue") {
    throw std::invalid_argument("unknown message '" + verb.substr(0, 32) + "' (expected cue)");
  }
  if (!(in >> cue.station >> kind_name >> param_text)) {
    throw std::invalid_argument("cue: expected 'cue STATION KIND PARAM|off'");
  }
  if (cue.station.size() > net::kMaxIdLength) {
    throw std::invalid_argument("cue: STATION longer than " + std::to_string(net::kMaxIdLength));
  }
  std::string extra;
  if (in >> extra) throw std::invalid_argument("cue: unexpected '" + extra.substr(0, 32) + "'");
  if (!cues::ParseCueKind(kind_name, &cue.kind)) {
    throw std::invalid_argument("cue: unknown kind '" + kind_name.substr(0, 32) + "' (" +
                                cues::CueKindNames() + ")");
  }
  cue.off = param_text == "off";
  if (!cue.off) {
    char* end = nullptr;
    cue.param = std::strtod(param_text.c_str(), &end);
    if (end == param_text.c_str() || *end != '\0' || !std::isfinite(cue.param)) {
      throw std::invalid_argument("cue: PARAM '" + param_text.substr(0, 32) +
                                  "' is neither a number nor off");
    }
  }
  if (const std::string why = cues::CheckCue(cue.kind, cue.param, cue.off); !why.empty()) {
    throw std::invalid_argument("cue: " + why);
  }
  return cue;
}

bool IsSessionMessage(const std::string& message) {
  std::istringstream in(message);
  std::string verb;
  in >> verb;
  return verb == "record" || verb == "replay";
}

std::string CheckRecordingName(const std::string& name) {
  if (name.empty()) return "an empty name";
  if (name.size() > 96) return "longer than 96 characters";
  if (name.front() == '.') return "starts with '.'";
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-';
    if (!ok) return "has a character other than letters, digits, '.', '_' and '-'";
  }
  if (!name.ends_with(".db") || name.size() == 3) return "does not end in .db";
  return "";
}

SessionCommand ParseSessionMessage(const std::string& message) {
  std::istringstream in(message);
  std::string verb, what;
  in >> verb >> what;
  std::vector<std::string> rest;
  for (std::string w; in >> w;) rest.push_back(w);
  SessionCommand c;
  const auto too_many = [&](std::size_t n) {
    if (rest.size() > n) {
      throw std::invalid_argument(verb + " " + what + ": unexpected '" + rest[n].substr(0, 64) +
                                  "'");
    }
  };
  // The command's FILE: the first argument, a recording's name.
  const auto file = [&] {
    if (rest.empty()) throw std::invalid_argument(verb + " " + what + ": expected FILE");
    if (const std::string why = CheckRecordingName(rest[0]); !why.empty()) {
      throw std::invalid_argument(verb + " " + what + ": FILE '" + rest[0].substr(0, 64) + "' " +
                                  why);
    }
    return rest[0];
  };
  // Argument k as a new recording's NAME: ".db" added when missing.
  const auto name = [&](std::size_t k) {
    std::string n = rest[k].ends_with(".db") ? rest[k] : rest[k] + ".db";
    if (const std::string why = CheckRecordingName(n); !why.empty()) {
      throw std::invalid_argument(verb + " " + what + ": NAME '" + rest[k].substr(0, 64) + "' " +
                                  why);
    }
    return n;
  };
  if (verb == "record") {
    if (what == "start") {
      too_many(1);
      c.verb = SessionCommand::Verb::kRecordStart;
      if (!rest.empty()) c.file = name(0);
      return c;
    }
    if (what == "stop") {
      too_many(0);
      c.verb = SessionCommand::Verb::kRecordStop;
      return c;
    }
    if (what == "delete") {
      too_many(1);
      c.verb = SessionCommand::Verb::kRecordDelete;
      c.file = file();
      return c;
    }
    if (what == "rename") {
      too_many(2);
      c.verb = SessionCommand::Verb::kRecordRename;
      c.file = file();
      if (rest.size() < 2) throw std::invalid_argument("record rename: expected FILE NAME");
      c.name = name(1);
      return c;
    }
    throw std::invalid_argument(
        "record: expected 'record start [NAME]', 'record stop', 'record delete FILE' or 'record "
        "rename FILE NAME'");
  }
  if (verb == "replay") {
    if (what == "play") {
      too_many(3);
      c.verb = SessionCommand::Verb::kReplayPlay;
      c.file = file();
      if (rest.size() > 1) c.speed = ParseNumber(rest[1], "replay play: SPEED");
      CheckSpeed(c.speed);
      if (rest.size() > 2) c.from_s = ParseNumber(rest[2], "replay play: FROM_S");
      if (c.from_s < 0) throw std::invalid_argument("replay play: FROM_S below 0");
      return c;
    }
    if (what == "pause" || what == "stop") {
      too_many(0);
      c.verb =
          what == "pause" ? SessionCommand::Verb::kReplayPause : SessionCommand::Verb::kReplayStop;
      return c;
    }
    if (what == "speed") {
      too_many(1);
      if (rest.empty()) throw std::invalid_argument("replay speed: expected SPEED");
      c.verb = SessionCommand::Verb::kReplaySpeed;
      c.speed = ParseNumber(rest[0], "replay speed: SPEED");
      CheckSpeed(c.speed);
      return c;
    }
    if (what == "add") {
      too_many(1);
      c.verb = SessionCommand::Verb::kReplayAdd;
      c.file = file();
      return c;
    }
    if (what == "seek") {
      too_many(1);
      if (rest.empty()) throw std::invalid_argument("replay seek: expected AT_S");
      c.verb = SessionCommand::Verb::kReplaySeek;
      c.from_s = ParseNumber(rest[0], "replay seek: AT_S");
      if (c.from_s < 0) throw std::invalid_argument("replay seek: AT_S below 0");
      return c;
    }
    throw std::invalid_argument(
        "replay: expected 'replay play FILE [SPEED [FROM_S]]', 'replay add FILE', 'replay pause', "
        "'replay speed SPEED', 'replay seek AT_S' or 'replay stop'");
  }
  throw std::invalid_argument("unknown message '" + verb.substr(0, 32) +
                              "' (expected record or replay)");
}

}  // namespace microdex::instructor
