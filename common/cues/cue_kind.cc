#include "common/cues/cue_kind.h"

namespace microdex::cues {

const char* CueKindName(CueKind kind) {
  switch (kind) {
    case CueKind::kClear:
      return "clear";
    case CueKind::kConvergentField:
      return "convergent";
    case CueKind::kDivergentField:
      return "divergent";
    case CueKind::kAmplifiedTremor:
      return "tremor";
  }
  return "unknown";
}

bool ParseCueKind(const std::string& name, CueKind* kind) {
  for (std::uint32_t i = 0; i < kCueKindCount; ++i) {
    if (name == CueKindName(static_cast<CueKind>(i))) {
      *kind = static_cast<CueKind>(i);
      return true;
    }
  }
  return false;
}

const char* CheckCue(CueKind kind, double param) {
  switch (kind) {
    case CueKind::kClear:
      return "";
    case CueKind::kConvergentField:
    case CueKind::kDivergentField:
      if (!(param > 0 && param <= kMaxFieldStiffness_N_per_m)) {
        return "stiffness: expected 0 < k <= 2000 N/m";
      }
      return "";
    case CueKind::kAmplifiedTremor:
      if (!(param >= 1 && param <= kMaxTremorGain)) return "gain: expected 1 <= gain <= 20";
      return "";
  }
  return "unknown cue kind";
}

}  // namespace microdex::cues
