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

}  // namespace microdex::cues
