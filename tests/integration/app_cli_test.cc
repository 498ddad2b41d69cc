// The command-line contracts (README.md): bad input exits 2 with one line on stderr naming
// the input; options of later issues are refused clearly rather than ignored.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/scene/scene.h"
#include "station/scene_run.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;

struct Outcome {
  int status = -1;
  std::string output;
};

Outcome RunApp(const std::string& binary, const std::vector<std::string>& args) {
  static int n = 0;
  const std::string log =
      "/tmp/microdex-cli-" + std::to_string(getpid()) + "-" + std::to_string(n++) + ".log";
  const pid_t pid = testing::Spawn(binary, args, log);
  const auto rc = testing::WaitExit(pid, 20000ms);
  if (!rc) testing::KillAll({pid});
  Outcome o{rc.value_or(-1), testing::ReadFile(log)};
  std::remove(log.c_str());
  return o;
}

void ExpectBadInput(const std::string& binary, const std::vector<std::string>& args,
                    const std::string& named) {
  const Outcome o = RunApp(binary, args);
  EXPECT_EQ(o.status, 2) << o.output;
  EXPECT_NE(o.output.find(named), std::string::npos) << o.output;
  EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
}

const std::string kScene = testing::SourceDir() + "/assets/scenes/needle_tube.yaml";

TEST(AppCli, StationRefusesBadInput) {
  ExpectBadInput("microdex-station", {"--scene", "/nonexistent.yaml"},
                 "microdex-station: /nonexistent.yaml: cannot open file\n");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--skill", "1.5"}, "--skill");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--device", "gui"}, "--device gui");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--window"}, "--window");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--security", "/tmp"}, "--security");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--domain", "999"}, "domain");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--dds-profile", "/no/such.xml"},
                 "/no/such.xml");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--station-id", "all"}, "--station-id");
  ExpectBadInput("microdex-station", {}, "--scene");
  ExpectBadInput("microdex-station", {"--scene", kScene, "--bogus"}, "--bogus");
}

std::string WriteScene(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// Bad scene files: one line "FILE:LINE: field: reason".
TEST(AppCli, StationNamesFileLineAndFieldOfABadScene) {
  const std::string head = "name: t\nmodules: [needle]\n";
  const std::string bad_value =
      WriteScene("cli_bad_value.yaml", head +
                                           "vessel:\n  core_radius_m: 5.0e-3\n"
                                           "  tube_radius_m: 6.0e-3\n");
  ExpectBadInput("microdex-station", {"--scene", bad_value},
                 "microdex-station: " + bad_value +
                     ":5: vessel.tube_radius_m: expected 0 < tube radius < core radius\n");
  const std::string bad_type = WriteScene("cli_bad_type.yaml", head + "haptic: {rate_hz: fast}\n");
  ExpectBadInput("microdex-station", {"--scene", bad_type},
                 "microdex-station: " + bad_type + ":3: haptic.rate_hz: expected a number\n");
  const std::string unknown = WriteScene("cli_unknown.yaml", head + "\ncolour: red\n");
  ExpectBadInput("microdex-station", {"--scene", unknown},
                 "microdex-station: " + unknown + ":4: colour: unknown key\n");
  const std::string malformed = WriteScene("cli_malformed.yaml", "name: t\nmodules: [needle\n");
  ExpectBadInput("microdex-station", {"--scene", malformed},
                 "microdex-station: " + malformed + ":3: malformed YAML: ");
  const std::string no_params = WriteScene("cli_no_params.yaml",
                                           "name: t\nmodules: [tissue]\n"
                                           "task: {path: line}\n"
                                           "tissue:\n  params: cli_no_such_tissue.yaml\n");
  ExpectBadInput("microdex-station", {"--scene", no_params},
                 "microdex-station: " + no_params + ":5: tissue.params: cannot open file " +
                     (std::filesystem::path(::testing::TempDir()) / "cli_no_such_tissue.yaml")
                         .lexically_normal()
                         .string() +
                     "\n");
}

// The same scene, skill, seed and simulated duration give the same steps, score and state hash
// whether the station is paced at 1 kHz or runs unpaced as fast as it can.
TEST(AppCli, UnpacedRunEqualsPacedRun) {
  const std::string dir = ::testing::TempDir();
  const auto run = [&](bool unpaced, const std::string& out) {
    std::vector<std::string> args = {"--scene",
                                     kScene,
                                     "--skill",
                                     "0.3",
                                     "--seed",
                                     "7",
                                     "--duration",
                                     "2",
                                     "--score-out",
                                     out,
                                     "--no-realtime",
                                     "--station-id",
                                     unpaced ? "unpaced" : "paced"};
    if (unpaced) args.push_back("--unpaced");
    const Outcome o = RunApp("microdex-station", args);
    EXPECT_EQ(o.status, 0) << o.output;
    return testing::ReadFile(out);
  };
  const std::string paced = run(false, dir + "/paced.json");
  const std::string unpaced = run(true, dir + "/unpaced.json");
  const auto field = [](const std::string& json, const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    if (at == std::string::npos) return std::string("(missing)");
    const size_t from = at + key.size() + 4;
    return json.substr(from, json.find_first_of(",\n", from) - from);
  };
  for (const char* key : {"steps", "score", "contacts", "time_in_contact_s", "mean_clearance_m",
                          "tremor_rms_m", "state_hash"}) {
    EXPECT_NE(field(paced, key), "(missing)") << key;
    EXPECT_EQ(field(paced, key), field(unpaced, key)) << key;
  }
  EXPECT_EQ(field(paced, "steps"), "2000");
}

// A training scene's station stops by itself when its task ends, and an unpaced station's
// final score is the one the in-process run (microdex-bench scores) computes for the same
// scene, skill and seed.
TEST(AppCli, StationStopsAtTaskEndWithTheSceneRunsScore) {
  const std::string scene_path = testing::SourceDir() + "/assets/scenes/tremor_hold.yaml";
  const std::string out = ::testing::TempDir() + "/tremor_hold.json";
  const Outcome o =
      RunApp("microdex-station", {"--scene", scene_path, "--skill", "0.4", "--seed", "3",
                                  "--unpaced", "--no-realtime", "--score-out", out});
  ASSERT_EQ(o.status, 0) << o.output;
  const std::string json = testing::ReadFile(out);
  const auto field = [&](const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    if (at == std::string::npos) return std::string("(missing)");
    const size_t from = at + key.size() + 4;
    return json.substr(from, json.find_first_of(",\n", from) - from);
  };
  EXPECT_EQ(field("outcome"), "\"completed\"");
  const scene::SceneModel scene = scene::LoadScene(scene_path);
  station::SimTraineeDef def;
  def.skill = 0.4;
  def.seed = 3;
  const station::SceneRunResult r = station::RunSceneWithTrainee(scene, def, 3);
  EXPECT_EQ(field("steps"), std::to_string(r.steps));
  EXPECT_NEAR(std::stod(field("score")), r.score.score, 1e-6);
  EXPECT_EQ(r.steps, 10000u);  // hold_s = 10 at 1 kHz
}

// Knot tying through the station: its publisher names the knot in the last thread frame it
// published, the scene run in its final state; the same knot (square for an expert, granny for
// a novice) and the same final score.
TEST(AppCli, KnotTyingStationNamesTheKnotAsTheSceneRunDoes) {
  const std::string scene_path = testing::SourceDir() + "/assets/scenes/knot_tying.yaml";
  const scene::SceneModel scene = scene::LoadScene(scene_path);
  for (const double skill : {0.9, 0.2}) {
    const std::string out = ::testing::TempDir() + "/knot_tying.json";
    const Outcome o = RunApp(
        "microdex-station", {"--scene", scene_path, "--skill", std::to_string(skill), "--seed", "3",
                             "--unpaced", "--no-realtime", "--score-out", out});
    ASSERT_EQ(o.status, 0) << o.output;
    const std::string json = testing::ReadFile(out);
    const std::string key = "\"metric\": \"knot_wrong\", \"value\": ";
    const size_t at = json.find(key);
    ASSERT_NE(at, std::string::npos) << json;
    const double knot_wrong = std::stod(json.substr(at + key.size()));
    EXPECT_EQ(knot_wrong, skill > 0.5 ? 0.0 : 1.0) << "skill " << skill;
    station::SimTraineeDef def;
    def.skill = skill;
    def.seed = 3;
    const station::SceneRunResult r = station::RunSceneWithTrainee(scene, def, 3);
    const size_t s = json.find("\"score\": ");
    ASSERT_NE(s, std::string::npos);
    EXPECT_NEAR(std::stod(json.substr(s + 9)), r.score.score, 1e-6) << "skill " << skill;
  }
}

TEST(AppCli, InstructorRefusesBadInput) {
  ExpectBadInput("microdex-instructor", {"--headless", "--cue", "st-1:vortex:3"}, "vortex");
  ExpectBadInput("microdex-instructor", {"--headless", "--cue", "st-1:tremor"}, "STATION:KIND");
  ExpectBadInput("microdex-instructor", {"--headless", "--cue", "st-1:tremor:x"}, "PARAM");
  ExpectBadInput("microdex-instructor", {"--headless", "--record", "/nonexistent-dir/a.db"},
                 "/nonexistent-dir/a.db: cannot create");
  ExpectBadInput("microdex-instructor", {}, "--headless");
  ExpectBadInput("microdex-instructor", {"--headless", "--partition", "a*"}, "partition");
}

TEST(AppCli, HelpExitsZero) {
  EXPECT_EQ(RunApp("microdex-station", {"--help"}).status, 0);
  EXPECT_EQ(RunApp("microdex-instructor", {"--help"}).status, 0);
}

}  // namespace
}  // namespace microdex
