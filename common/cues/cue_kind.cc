#include "common/cues/cue_kind.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace microdex::cues {
namespace {

struct KindInfo {
  const char* name;
  CueParamRange range;
};

// In CueKind order.
constexpr KindInfo kKinds[kCueKindCount] = {
    {"clear", {0, 0, 0, "param"}},
    {"convergent", {0, kMaxFieldStiffness_N_per_m, 200, "stiffness_N_per_m"}},
    {"divergent", {0, kMaxFieldStiffness_N_per_m, 100, "stiffness_N_per_m"}},
    {"amplified_tremor", {1, kMaxTremorGain, 3, "gain"}},
    {"visual_path", {0, 1e-3, 50e-6, "width_m"}},
    {"visual_limits", {0, kMaxCueDistance_m, 0, "half_width_m"}},
    {"visual_deviation", {0, kMaxCueDistance_m, 0, "full_scale_m"}},
    {"visual_clearance", {1e-6, kMaxCueDistance_m, 1e-3, "range_m"}},
    {"audio_click", {0, 1, 0.8, "volume"}},
    {"audio_error", {0, 1, 0.5, "volume"}},
    {"audio_proximity", {1e-6, kMaxCueDistance_m, 1e-3, "range_m"}},
    {"audio_geiger", {1e-6, kMaxCueDistance_m, 1e-3, "range_m"}},
    {"wall", {0, kMaxWallGain, 1, "gain"}},
    {"predictive", {1e-6, kMaxCueDistance_m, 0.5e-3, "error_m"}},
};

constexpr bool DefaultsAgree() {
  for (std::uint32_t i = 0; i < kCueKindCount; ++i) {
    if (kKinds[i].range.default_value != kCueParamDefaults[i]) return false;
  }
  return true;
}
static_assert(DefaultsAgree(), "kCueParamDefaults and the table of kinds agree");

}  // namespace

const char* CueKindName(CueKind kind) {
  const auto i = static_cast<std::uint32_t>(kind);
  return i < kCueKindCount ? kKinds[i].name : "unknown";
}

const char* CueKindNames() {
  return "clear, convergent, divergent, amplified_tremor, visual_path, visual_limits, "
         "visual_deviation, visual_clearance, audio_click, audio_error, audio_proximity, "
         "audio_geiger, wall, predictive";
}

bool ParseCueKind(const std::string& name, CueKind* kind) {
  if (name == "tremor") {  // the name of the first release
    *kind = CueKind::kAmplifiedTremor;
    return true;
  }
  for (std::uint32_t i = 0; i < kCueKindCount; ++i) {
    if (name == kKinds[i].name) {
      *kind = static_cast<CueKind>(i);
      return true;
    }
  }
  return false;
}

CueParamRange CueParamLimits(CueKind kind) {
  const auto i = static_cast<std::uint32_t>(kind);
  return i < kCueKindCount ? kKinds[i].range : CueParamRange{};
}

bool IsCueValid(CueKind kind, double param, bool off) {
  const auto i = static_cast<std::uint32_t>(kind);
  if (i >= kCueKindCount) return false;
  if (off || kind == CueKind::kClear) return true;
  const CueParamRange& r = kKinds[i].range;
  return std::isfinite(param) && param >= r.min && param <= r.max;
}

std::string CheckCue(CueKind kind, double param, bool off) {
  if (IsCueValid(kind, param, off)) return {};
  const auto i = static_cast<std::uint32_t>(kind);
  if (i >= kCueKindCount) return "kind: unknown cue kind " + std::to_string(i);
  const CueParamRange& r = kKinds[i].range;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s: expected a finite number in [%g, %g] for %s, got %g", r.name,
                r.min, r.max, kKinds[i].name, param);
  return buf;
}

CueArg ParseCueArg(const std::string& text) {
  CueArg a;
  const std::size_t colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  if (!ParseCueKind(kind, &a.kind)) {
    throw std::invalid_argument("'" + text + "': KIND '" + kind + "' is not one of " +
                                CueKindNames());
  }
  a.param = CueParamLimits(a.kind).default_value;
  if (colon != std::string::npos) {
    const std::string p = text.substr(colon + 1);
    if (p == "off") {
      a.off = true;
    } else {
      std::size_t used = 0;
      double v = 0;
      try {
        v = std::stod(p, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (p.empty() || used != p.size()) {
        throw std::invalid_argument("'" + text + "': PARAM '" + p + "' is not a number");
      }
      a.param = v;
    }
  }
  if (const std::string why = CheckCue(a.kind, a.param, a.off); !why.empty()) {
    throw std::invalid_argument("'" + text + "': " + why);
  }
  return a;
}

}  // namespace microdex::cues
