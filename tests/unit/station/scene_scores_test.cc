// The training scenes' scores tell a skilled simulated trainee from a novice (the shorter run
// of `microdex-bench scores`): for every training scene in assets/scenes, the mean score of
// three seeds rises strictly with skill (0.2, 0.5, 0.9), by at least 20 points from 0.2 to
// 0.9; every run ends by itself (completed, or at the time limit) and scores within 0..100.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/scene/scene.h"
#include "station/scene_run.h"

namespace microdex::station {
namespace {

std::string ScenesDir() {
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(root != nullptr ? root : ".") + "/assets/scenes";
}

double MeanScore(const scene::SceneModel& scene, double skill) {
  double sum = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SimTraineeDef def;
    def.skill = skill;
    def.seed = seed;
    const SceneRunResult r = RunSceneWithTrainee(scene, def, seed);
    EXPECT_NE(r.score.outcome, 0) << scene.name << " skill " << skill << " did not end";
    EXPECT_GE(r.score.score, 0);
    EXPECT_LE(r.score.score, 100);
    sum += r.score.score;
  }
  return sum / 3;
}

class SceneScores : public ::testing::TestWithParam<const char*> {};

TEST_P(SceneScores, RiseWithSkill) {
  const std::string path = ScenesDir() + "/" + GetParam() + ".yaml";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << ": not a scene of this build";
  const scene::SceneModel scene = scene::LoadScene(path);
  ASSERT_NE(scene.task.kind, scene::TaskKind::kFollowPath) << path;
  const double novice = MeanScore(scene, 0.2);
  const double middle = MeanScore(scene, 0.5);
  const double expert = MeanScore(scene, 0.9);
  EXPECT_LT(novice, middle) << GetParam();
  EXPECT_LT(middle, expert) << GetParam();
  EXPECT_GE(expert - novice, 20) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(TrainingScenes, SceneScores,
                         ::testing::Values("tremor_hold", "loop_along_wire", "needle_along_tube",
                                           "grasp", "nylon_loop", "knot_topology", "knot_placement",
                                           "needle_through_tissue", "knot_tying"),
                         [](const auto& p) { return std::string(p.param); });

}  // namespace
}  // namespace microdex::station
