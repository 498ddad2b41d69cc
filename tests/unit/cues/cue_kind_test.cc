// Cue kinds: every kind has a name that parses back to it, a default inside its limits, and a
// parameter check that rejects non-finite numbers and values beyond the limits by name.
#include "common/cues/cue_kind.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace microdex::cues {
namespace {

TEST(CueKind, EveryKindByNameWithItsDefault) {
  const char* names[] = {"clear",       "convergent",    "divergent",        "amplified_tremor",
                         "visual_path", "visual_limits", "visual_deviation", "visual_clearance",
                         "audio_click", "audio_error",   "audio_proximity",  "audio_geiger",
                         "wall",        "predictive"};
  ASSERT_EQ(std::size(names), kCueKindCount);
  for (std::uint32_t k = 0; k < kCueKindCount; ++k) {
    const auto kind = static_cast<CueKind>(k);
    EXPECT_STREQ(CueKindName(kind), names[k]);
    CueKind parsed{};
    ASSERT_TRUE(ParseCueKind(names[k], &parsed)) << names[k];
    EXPECT_EQ(parsed, kind);
    EXPECT_NE(std::string(CueKindNames()).find(names[k]), std::string::npos) << names[k];
    const CueParamRange r = CueParamLimits(kind);
    EXPECT_EQ(CheckCue(kind, r.default_value), "") << names[k];
    const CueArg a = ParseCueArg(names[k]);
    EXPECT_EQ(a.kind, kind);
    EXPECT_EQ(a.param, r.default_value);
    EXPECT_FALSE(a.off);
  }
  CueKind parsed{};
  EXPECT_TRUE(ParseCueKind("tremor", &parsed)) << "the first release's name still reads";
  EXPECT_EQ(parsed, CueKind::kAmplifiedTremor);
  EXPECT_FALSE(ParseCueKind("vortex", &parsed));
}

TEST(CueKind, ParametersAtAndBeyondTheirLimits) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (std::uint32_t k = 1; k < kCueKindCount; ++k) {
    const auto kind = static_cast<CueKind>(k);
    SCOPED_TRACE(CueKindName(kind));
    const CueParamRange r = CueParamLimits(kind);
    EXPECT_EQ(CheckCue(kind, r.min), "");
    EXPECT_EQ(CheckCue(kind, r.max), "");
    for (double bad : {nan, inf, -inf, r.max * 1.001 + 1e-9, r.min - 1e-3 - std::abs(r.min)}) {
      const std::string why = CheckCue(kind, bad);
      EXPECT_EQ(why.rfind(r.name, 0), 0u) << "names the parameter: " << why;
    }
    EXPECT_EQ(CheckCue(kind, nan, /*off=*/true), "") << "off takes no parameter";
  }
  // The stiffness range of the fields is 0 .. 1e6 N/m (the force limiter keeps it stable).
  EXPECT_EQ(CheckCue(CueKind::kConvergentField, 0), "");
  EXPECT_EQ(CheckCue(CueKind::kDivergentField, 1e6), "");
  EXPECT_NE(CheckCue(static_cast<CueKind>(kCueKindCount), 1), "");
}

// The haptic thread's yes/no check is the same rule as the message-building one, over every
// kind (and one past the last), on and off, at, inside and beyond each limit.
TEST(CueKind, TheAllocationFreeCheckAgreesWithTheMessage) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  int valid = 0, invalid = 0;
  for (std::uint32_t k = 0; k <= kCueKindCount; ++k) {
    const auto kind = static_cast<CueKind>(k);
    const CueParamRange r = k < kCueKindCount ? CueParamLimits(kind) : CueParamRange{};
    for (double p : {nan, inf, -inf, r.min, r.max, 0.5 * (r.min + r.max), r.max * 1.001 + 1e-9,
                     r.min - 1e-3 - std::abs(r.min)}) {
      for (bool off : {false, true}) {
        const bool ok = IsCueValid(kind, p, off);
        EXPECT_EQ(ok, CheckCue(kind, p, off).empty()) << k << " " << p << " " << off;
        (ok ? valid : invalid) += 1;
      }
    }
  }
  EXPECT_GT(valid, 0);
  EXPECT_GT(invalid, 0);
}

TEST(CueKind, CommandLineArgument) {
  const CueArg a = ParseCueArg("convergent:350");
  EXPECT_EQ(a.kind, CueKind::kConvergentField);
  EXPECT_EQ(a.param, 350);
  const CueArg off = ParseCueArg("wall:off");
  EXPECT_EQ(off.kind, CueKind::kWall);
  EXPECT_TRUE(off.off);
  for (const char* bad :
       {"convergent:nan", "convergent:inf", "convergent:2e6", "convergent:x",
        "convergent:", "audio_click:1.5", "amplified_tremor:0.5", "vortex:1", "predictive:-1"}) {
    try {
      ParseCueArg(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(std::string("'") + bad + "'", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace microdex::cues
