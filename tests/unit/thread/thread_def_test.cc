// ThreadDef: presets, the YAML parameter files and their error messages.
#include "common/thread/thread_def.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

namespace microdex::thread {
namespace {

std::string SourceDir() {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return dir != nullptr ? dir : ".";
}

std::string ErrorOf(const std::string& path) {
  try {
    LoadThreadDef(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ThreadDef, PresetsValidateAndMatchTheirFiles) {
  const std::pair<const char*, ThreadDef> cases[] = {
      {"thread_stiff_nylon_10_0.yaml", StiffNylon10_0()},
      {"thread_soft_silk.yaml", SoftSilk()},
      {"thread_necklace.yaml", Necklace()}};
  for (const auto& [file, preset] : cases) {
    preset.Validate();
    const ThreadDef loaded = LoadThreadDef(SourceDir() + "/assets/scenes/" + file);
    EXPECT_EQ(loaded.name, preset.name);
    EXPECT_EQ(loaded.num_nodes, preset.num_nodes);
    EXPECT_DOUBLE_EQ(loaded.diameter_m, preset.diameter_m);
    EXPECT_DOUBLE_EQ(loaded.youngs_modulus_Pa, preset.youngs_modulus_Pa);
    EXPECT_DOUBLE_EQ(loaded.contact_force_N, preset.contact_force_N);
    EXPECT_DOUBLE_EQ(loaded.bend_stiffness_N_m, preset.bend_stiffness_N_m);
  }
}

TEST(ThreadDef, ValidateNamesTheBadField) {
  ThreadDef def = StiffNylon10_0();
  def.diameter_m = -1.0;
  try {
    def.Validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("diameter_m"), std::string::npos);
  }
}

TEST(ThreadDef, BadFilesNameFileAndField) {
  const std::string dir = ::testing::TempDir();
  const std::string missing = dir + "/no_such_thread.yaml";
  EXPECT_NE(ErrorOf(missing).find("no_such_thread.yaml"), std::string::npos);
  const std::string bad_type = dir + "/bad_type.yaml";
  std::ofstream(bad_type) << "thread:\n  diameter_m: thick\n";
  EXPECT_NE(ErrorOf(bad_type).find("diameter_m"), std::string::npos);
  EXPECT_NE(ErrorOf(bad_type).find("bad_type.yaml"), std::string::npos);
  const std::string unknown = dir + "/unknown.yaml";
  std::ofstream(unknown) << "thread:\n  stifness: 3\n";
  EXPECT_NE(ErrorOf(unknown).find("stifness"), std::string::npos);
  const std::string invalid = dir + "/invalid.yaml";
  std::ofstream(invalid) << "thread:\n  base: necklace\n  num_nodes: 1\n";
  EXPECT_NE(ErrorOf(invalid).find("num_nodes"), std::string::npos);
}

}  // namespace
}  // namespace microdex::thread
