#pragma once
// The kinds of learning cue a station applies (thesis §2.1, §4.1), their command-line names,
// their one parameter (its unit, default and limits) and its check. The DDS type has its own
// enum (idl/cue_command.idl); common/net converts between them enumerator by enumerator.
// README.md in this folder describes every cue and its formula.

#include <array>
#include <cstdint>
#include <string>

namespace microdex::cues {

enum class CueKind : std::uint32_t {
  kClear = 0,            // remove every active cue (the wall stays as the scene set it)
  kConvergentField = 1,  // param: stiffness, N/m
  kDivergentField = 2,   // param: stiffness, N/m
  kAmplifiedTremor = 3,  // param: gain >= 1
  kVisualPath = 4,       // param: line width, m
  kVisualLimits = 5,     // param: half-width of the allowed band, m (0: the task's tolerance)
  kVisualDeviation = 6,  // param: deviation drawn full red, m (0: the task's tolerance)
  kVisualClearance = 7,  // param: clearance drawn green and above, m
  kAudioClick = 8,       // param: volume 0..1
  kAudioError = 9,       // param: volume 0..1
  kAudioProximity = 10,  // param: clearance below which the tone sounds, m
  kAudioGeiger = 11,     // param: clearance below which the counter clicks, m
  kWall = 12,            // param: gain on the scene's wall stiffness, 0..10 (1: as the scene)
  kPredictive = 13,      // param: end-point error that raises the warning, m
};
inline constexpr std::uint32_t kCueKindCount = 14;

// Each kind's default parameter, in CueKind order (CueParamLimits(kind).default_value): what a
// fresh state holds and what `--cue KIND` without a parameter means.
inline constexpr std::array<double, kCueKindCount> kCueParamDefaults = {
    0, 200, 100, 3, 50e-6, 0, 0, 1e-3, 0.8, 0.5, 1e-3, 1e-3, 1, 0.5e-3};

// The command-line name of a kind: clear, convergent, divergent, amplified_tremor,
// visual_path, visual_limits, visual_deviation, visual_clearance, audio_click, audio_error,
// audio_proximity, audio_geiger, wall, predictive.
const char* CueKindName(CueKind kind);
// False when the name is none of those (the older name "tremor" still reads as
// amplified_tremor).
bool ParseCueKind(const std::string& name, CueKind* kind);
// Every name, comma separated (for error messages and --help).
const char* CueKindNames();

// The bit of a kind in a mask of active cues.
constexpr std::uint32_t CueBit(CueKind kind) { return 1u << static_cast<std::uint32_t>(kind); }

// The limits of each kind's parameter. A request outside them is rejected before it reaches
// the simulation (and a scene's default cue outside them is a bad scene).
struct CueParamRange {
  double min = 0;
  double max = 0;
  double default_value = 0;  // what `--cue KIND` without a parameter means
  const char* name = "";     // "stiffness_N_per_m", ...
};
CueParamRange CueParamLimits(CueKind kind);

inline constexpr double kMaxFieldStiffness_N_per_m = 1e6;
inline constexpr double kMaxTremorGain = 20;
inline constexpr double kMaxWallGain = 10;
inline constexpr double kMaxCueDistance_m = 0.05;  // visual and audio ranges, warning distance

// Empty when the cue can be applied (switching a cue off is always possible); otherwise why
// not, naming the parameter: "stiffness_N_per_m: expected a finite number in [0, 1e+06]".
std::string CheckCue(CueKind kind, double param, bool off = false);
// The same rule as a yes/no, without building a message: allocation-free, for the haptic
// thread (CheckCue(k, p, off).empty() == IsCueValid(k, p, off)).
bool IsCueValid(CueKind kind, double param, bool off = false);

// A cue as written on a command line: KIND, KIND:PARAM or KIND:off.
struct CueArg {
  CueKind kind = CueKind::kClear;
  double param = 0;
  bool off = false;
};
// Parses "KIND[:PARAM|:off]" (the parameter defaults to the kind's); throws
// std::invalid_argument("'TEXT': reason") for an unknown kind, a parameter that is not a number,
// or one out of its limits.
CueArg ParseCueArg(const std::string& text);

}  // namespace microdex::cues
