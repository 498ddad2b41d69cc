// microdex-bench grasp in its quick mode: it runs and writes JSON of the documented shape
// (parsed with yaml-cpp, JSON being YAML), with errors against the analytic values that agree
// with the unit tests' bounds.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <string>

namespace {

TEST(GraspBench, QuickJsonShape) {
  const char* bin = std::getenv("MICRODEX_BIN_DIR");
  const std::string json = ::testing::TempDir() + "/grasp.json";
  const std::string cmd = std::string(bin != nullptr ? bin : "bin") +
                          "/microdex-bench grasp --quick --json " + json + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const YAML::Node root = YAML::LoadFile(json);
  ASSERT_TRUE(root["settings"].IsSequence());
  EXPECT_EQ(root["settings"].size(), 2u);  // 5 and 20 iterations, 1 sub-step
  for (const auto& s : root["settings"]) {
    EXPECT_GE(s["iterations"].as<int>(), 1);
    EXPECT_EQ(s["substeps"].as<int>(), 1);
    EXPECT_LT(s["hold_error"].as<double>(), 0.03);
    EXPECT_LT(s["slide_error"].as<double>(), 0.01);
    EXPECT_GE(s["aligned_rotation_rad"].as<double>(), 0.0);
    EXPECT_GT(s["step_median_us"].as<double>(), 0.0);
    EXPECT_NEAR(s["hold_exact_N"].as<double>(), 1e-6 * 9.81 / (2.0 * 0.5), 1e-12);
  }
}

}  // namespace
