#include "instructor/cue_spec.h"

#include <cmath>
#include <stdexcept>

namespace microdex::instructor {
namespace {

double ParseNumber(const std::string& s, const std::string& text, const char* what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size() || s.empty() || !std::isfinite(v)) {
    throw std::invalid_argument("--cue '" + text + "': " + what + " '" + s + "' is not a number");
  }
  return v;
}

}  // namespace

CueSpec ParseCueSpec(const std::string& text) {
  const auto c1 = text.find(':');
  const auto c2 = c1 == std::string::npos ? c1 : text.find(':', c1 + 1);
  if (c1 == std::string::npos || c2 == std::string::npos) {
    throw std::invalid_argument("--cue '" + text + "': expected STATION:KIND:PARAM[@SECONDS]");
  }
  CueSpec spec;
  spec.station = text.substr(0, c1);
  if (spec.station.empty() || spec.station.size() > net::kMaxIdLength) {
    throw std::invalid_argument("--cue '" + text + "': STATION must be 1..64 characters or 'all'");
  }
  const std::string kind = text.substr(c1 + 1, c2 - c1 - 1);
  if (!cues::ParseCueKind(kind, &spec.kind)) {
    throw std::invalid_argument("--cue '" + text + "': KIND '" + kind +
                                "' is not one of clear, convergent, divergent, tremor");
  }
  std::string rest = text.substr(c2 + 1);
  if (const auto at = rest.find('@'); at != std::string::npos) {
    spec.at_s = ParseNumber(rest.substr(at + 1), text, "SECONDS");
    if (spec.at_s < 0) throw std::invalid_argument("--cue '" + text + "': SECONDS must be >= 0");
    rest = rest.substr(0, at);
  }
  spec.param = ParseNumber(rest, text, "PARAM");
  return spec;
}

}  // namespace microdex::instructor
