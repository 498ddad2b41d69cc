#pragma once
// The kinds of learning cue a station applies (thesis §2.1). The DDS type has its own enum
// (idl/cue_command.idl); common/net converts between them enumerator by enumerator.

#include <cstdint>
#include <string>

namespace microdex::cues {

enum class CueKind : std::uint32_t {
  kClear,            // remove every active cue
  kConvergentField,  // param: stiffness, N/m
  kDivergentField,   // param: stiffness, N/m
  kAmplifiedTremor,  // param: gain >= 1
};
inline constexpr std::uint32_t kCueKindCount = 4;

// The command-line name of a kind: clear, convergent, divergent, tremor.
const char* CueKindName(CueKind kind);
// False when the name is none of those.
bool ParseCueKind(const std::string& name, CueKind* kind);

// Cue limits: a request outside them is rejected before it reaches the simulation (and a
// scene's default cue outside them is a bad scene).
inline constexpr double kMaxFieldStiffness_N_per_m = 2000;
inline constexpr double kMaxTremorGain = 20;
// Empty when the cue can be applied; otherwise why not ("stiffness: expected ...").
const char* CheckCue(CueKind kind, double param);

}  // namespace microdex::cues
