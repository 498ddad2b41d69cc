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
  if (c1 == std::string::npos) {
    throw std::invalid_argument("--cue '" + text +
                                "': expected STATION:KIND:PARAM[@SECONDS] (PARAM may be 'off')");
  }
  CueSpec spec;
  spec.station = text.substr(0, c1);
  if (spec.station.empty() || spec.station.size() > net::kMaxIdLength) {
    throw std::invalid_argument("--cue '" + text + "': STATION must be 1..64 characters or 'all'");
  }
  std::string rest = text.substr(c1 + 1);
  if (rest.find(':') == std::string::npos) {
    throw std::invalid_argument("--cue '" + text +
                                "': expected STATION:KIND:PARAM[@SECONDS] (PARAM may be 'off')");
  }
  if (const auto at = rest.find('@'); at != std::string::npos) {
    spec.at_s = ParseNumber(rest.substr(at + 1), text, "SECONDS");
    if (spec.at_s < 0) throw std::invalid_argument("--cue '" + text + "': SECONDS must be >= 0");
    rest = rest.substr(0, at);
  }
  try {
    const cues::CueArg a = cues::ParseCueArg(rest);
    spec.kind = a.kind;
    spec.param = a.param;
    spec.off = a.off;
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--cue '" + text + "': " + e.what());
  }
  return spec;
}

}  // namespace microdex::instructor
