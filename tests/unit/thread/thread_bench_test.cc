// microdex-bench thread in its quick mode: each report runs and writes JSON of the documented
// shape (parsed with yaml-cpp, JSON being YAML).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
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

// --tie: per phase and at the end the knot, the brute-force minimum distance, held, the median
// rate and the tick p99 (the report contract).
TEST(ThreadBench, TieJsonShape) {
  const YAML::Node root = RunBench("--tie 1r --nodes 129 --friction 0.1", "tie");
  EXPECT_EQ(root["throws"].as<std::string>(), "1r");
  EXPECT_EQ(root["nodes"].as<int>(), 129);
  EXPECT_FALSE(root["knot"].as<std::string>().empty());
  EXPECT_GT(root["min_distance_over_d"].as<double>(), 0.0);
  (void)root["held"].as<bool>();
  EXPECT_GT(root["steps_per_s"].as<double>(), 0.0);
  EXPECT_GT(root["tick_p99_us"].as<double>(), 0.0);
  ASSERT_TRUE(root["phases"].IsSequence());
  ASSERT_GE(root["phases"].size(), 6u);  // loop, helix, exit, release, pull, hold
  for (const auto& phase : root["phases"]) {
    EXPECT_FALSE(phase["phase"].as<std::string>().empty());
    EXPECT_FALSE(phase["knot"].as<std::string>().empty());
    EXPECT_GT(phase["min_distance_over_d"].as<double>(), 0.0);
    EXPECT_GT(phase["steps_per_s"].as<double>(), 0.0);
    EXPECT_GT(phase["tick_p99_us"].as<double>(), 0.0);
    // Every step projects its motion in at least one part, each of at least one sweep.
    const double parts = phase["projection_parts_per_step"].as<double>();
    EXPECT_GE(parts, 1.0);
    EXPECT_GE(phase["projection_sweeps_per_step"].as<double>(), parts);
    EXPECT_LE(phase["projection_sweeps_per_step"].as<double>(),
              parts * phase["max_projection_sweeps"].as<double>() + 1e-9);
  }
  EXPECT_EQ(root["phases"][root["phases"].size() - 1]["phase"].as<std::string>(), "hold");
}

// --tie-matrix in its quick mode (the five knots at 129 nodes, μ 0.2): every knot ties and holds
// at the matrix's pull tension (the bench exits 0 only then), the JSON says the tension, and
// the markdown is the README's table: a row per case with the README's eleven columns.
TEST(ThreadBench, TieMatrixQuickTiesAndHoldsEveryKnot) {
  const std::string markdown = ::testing::TempDir() + "/tie_matrix.md";
  const YAML::Node root = RunBench("--tie-matrix --markdown " + markdown, "tie_matrix");
  EXPECT_DOUBLE_EQ(root["pull_tension_N"].as<double>(), 0.015);
  ASSERT_TRUE(root["runs"].IsSequence());
  ASSERT_EQ(root["runs"].size(), 5u);
  const char* expected[] = {"overhand-right", "double-overhand", "square", "granny", "surgeons"};
  for (std::size_t k = 0; k < 5; ++k) {
    const YAML::Node run = root["runs"][k];
    EXPECT_EQ(run["knot"].as<std::string>(), expected[k]) << k;
    EXPECT_TRUE(run["held"].as<bool>()) << k;
    EXPECT_TRUE(run["pulled_tight"].as<bool>()) << k;
    EXPECT_GE(run["min_distance_over_d"].as<double>(), 0.95) << k;
  }
  std::ifstream in(markdown);
  ASSERT_TRUE(in.good()) << markdown;
  int rows = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| ", 0) != 0 || line.rfind("| knot ", 0) == 0) continue;
    EXPECT_EQ(std::count(line.begin(), line.end(), '|'), 12) << line;
    EXPECT_NE(line.find("| yes |"), std::string::npos) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 5);
}

}  // namespace
