// Experiment files: a valid one read, bad ones refused with FILE:LINE: field: reason; the
// assignment of trainees to conditions randomised by the seed and balanced.

#include "common/scores/experiment.h"

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "common/base/input_error.h"

namespace microdex::scores {
namespace {

constexpr const char* kGood = R"(name: pilot
scene: tremor_hold.yaml
seed: 7
trials_per_trainee: 5
conditions:
  none: []
  audio: [audio_click:0.8]
  guidance: [convergent:300, audio_click:off]
trainees: [ana, ben, chloe, dan, eva, finn, gus]
)";

// The error of parsing `text` (which must fail).
InputError ErrorOf(const std::string& text) {
  try {
    ParseExperiment(text, "exp.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return InputError("", 0, "", "");
}

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

TEST(Experiment, ReadsAValidFile) {
  const ExperimentDef e = ParseExperiment(kGood, "exp.yaml");
  EXPECT_EQ(e.name, "pilot");
  EXPECT_EQ(e.seed, 7u);
  EXPECT_EQ(e.trials_per_trainee, 5);
  ASSERT_EQ(e.conditions.size(), 3u);
  EXPECT_EQ(e.conditions[0].name, "none");  // in the file's order
  EXPECT_TRUE(e.conditions[0].cues.empty());
  EXPECT_EQ(e.conditions[2].name, "guidance");
  ASSERT_EQ(e.conditions[2].cues.size(), 2u);
  EXPECT_EQ(e.conditions[2].cues[0].kind, cues::CueKind::kConvergentField);
  EXPECT_DOUBLE_EQ(e.conditions[2].cues[0].param, 300);
  EXPECT_TRUE(e.conditions[2].cues[1].off);
  EXPECT_EQ(e.trainees.size(), 7u);
}

TEST(Experiment, BadFilesNameTheLineAndTheField) {
  struct Case {
    std::string text;
    int line;
    std::string field;
  };
  const Case cases[] = {
      {Replace(kGood, "trials_per_trainee: 5", "trials_per_trainee: 0"), 4, "trials_per_trainee"},
      {Replace(kGood, "trials_per_trainee: 5", "trials_per_trainee: five"), 4,
       "trials_per_trainee"},
      {Replace(kGood, "audio: [audio_click:0.8]", "audio: [audio_click:7]"), 7, "conditions.audio"},
      {Replace(kGood, "audio: [audio_click:0.8]", "audio: [loud_noise]"), 7, "conditions.audio"},
      {Replace(kGood, "audio: [audio_click:0.8]", "audio: audio_click"), 7, "conditions.audio"},
      {Replace(kGood, "seed: 7", "seed: 7\ncolour: blue"), 4, "colour"},
      {Replace(kGood, "trainees: [ana, ben, chloe, dan, eva, finn, gus]",
               "trainees: [ana, ana, b]"),
       9, "trainees"},
      {Replace(kGood, "trainees: [ana, ben, chloe, dan, eva, finn, gus]", "trainees: [ana, ben]"),
       9, "trainees"},
      {Replace(kGood, "  audio: [audio_click:0.8]\n  guidance: [convergent:300, audio_click:off]\n",
               ""),
       5, "conditions"},
      {Replace(kGood, "scene: tremor_hold.yaml\n", ""), 1, "scene"},
  };
  for (const Case& c : cases) {
    const InputError e = ErrorOf(c.text);
    EXPECT_EQ(e.file(), "exp.yaml") << c.text;
    EXPECT_EQ(e.line(), c.line) << e.what() << "\n" << c.text;
    EXPECT_EQ(e.field(), c.field) << e.what() << "\n" << c.text;
    EXPECT_FALSE(e.reason().empty());
  }
  // Not YAML at all: the line yaml-cpp stopped at.
  const InputError broken = ErrorOf("name: pilot\nconditions: {none: [\n");
  EXPECT_EQ(broken.file(), "exp.yaml");
  EXPECT_GT(broken.line(), 0) << broken.what();
  // A missing file.
  try {
    ReadExperiment("/nonexistent/exp.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/exp.yaml: cannot open file");
  }
}

TEST(Experiment, AssignmentIsBalancedAndSeeded) {
  ExperimentDef e = ParseExperiment(kGood, "exp.yaml");
  const auto a = AssignConditions(e);
  ASSERT_EQ(a.size(), 7u);
  std::map<std::string, int> sizes;
  for (const auto& [trainee, condition] : a) ++sizes[condition];
  ASSERT_EQ(sizes.size(), 3u);
  for (const auto& [condition, n] : sizes) {
    EXPECT_GE(n, 2) << condition;  // 7 over 3: sizes 3, 2, 2
    EXPECT_LE(n, 3) << condition;
  }
  EXPECT_EQ(AssignConditions(e), a);  // the same seed, the same assignment
  int differ = 0;
  for (std::uint64_t seed = 100; seed < 110; ++seed) {
    e.seed = seed;
    differ += AssignConditions(e) != a ? 1 : 0;
  }
  EXPECT_GE(differ, 8);  // other seeds shuffle differently (1260 assignments of 7 into 3, 2, 2)
}

}  // namespace
}  // namespace microdex::scores
