// microdex-bench thread in its quick mode: each report runs and writes JSON of the documented
// shape (parsed with yaml-cpp, JSON being YAML).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <string>

namespace {

YAML::Node RunBench(const std::string& args, const std::string& name) {
  const char* bin = std::getenv("MICRODEX_BIN_DIR");
  const std::string json = ::testing::TempDir() + "/" + name + ".json";
  const std::string cmd = std::string(bin != nullptr ? bin : "bin") + "/microdex-bench thread " +
                          args + " --quick --json " + json + " > /dev/null";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return YAML::LoadFile(json);
}

TEST(ThreadBench, SpeedJsonShape) {
  const YAML::Node root = RunBench("", "speed");
  ASSERT_TRUE(root["runs"].IsSequence());
  EXPECT_EQ(root["runs"].size(), 4u);  // 2 integrators x 2 sizes in quick mode
  for (const auto& run : root["runs"]) {
    EXPECT_FALSE(run["integrator"].as<std::string>().empty());
    EXPECT_GE(run["nodes"].as<int>(), 65);
    EXPECT_GT(run["steps_per_s"].as<double>(), 0.0);
    EXPECT_GT(run["collision_ns"].as<double>(), 0.0);
  }
  EXPECT_GT(root["bvh_vs_all_pairs"]["ratio"].as<double>(), 0.0);
  EXPECT_EQ(root["bvh_vs_all_pairs"]["pairs"].as<int>(),
            root["bvh_vs_all_pairs"]["all_pairs_pairs"].as<int>());
}

TEST(ThreadBench, StabilityJsonShape) {
  const YAML::Node root = RunBench("--stability", "stability");
  ASSERT_TRUE(root["runs"].IsSequence());
  EXPECT_EQ(root["runs"].size(), 8u);  // 2 integrators x 2 k_s x 2 dt
  for (const auto& run : root["runs"]) {
    EXPECT_GT(run["dt_s"].as<double>(), 0.0);
    (void)run["stable"].as<bool>();
  }
  EXPECT_EQ(root["summary"].size(), 2u);
}

TEST(ThreadBench, AccuracyJsonShape) {
  const YAML::Node root = RunBench("--accuracy", "accuracy");
  ASSERT_TRUE(root["runs"].IsSequence());
  EXPECT_EQ(root["runs"].size(), 4u);
  for (const auto& run : root["runs"]) {
    EXPECT_GT(run["ns_per_step"].as<double>(), 0.0);
    EXPECT_GE(run["position_error_m"].as<double>(), 0.0);
  }
}

}  // namespace
