#include "instructor/console_message.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "common/net/messages.h"

namespace microdex::instructor {

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

}  // namespace microdex::instructor
