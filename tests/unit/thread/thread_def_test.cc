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
    EXPECT_EQ(loaded.friction_contacts, preset.friction_contacts);
    EXPECT_EQ(loaded.friction_self_contacts, preset.friction_self_contacts);
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

TEST(ThreadDef, FrictionSelfContactsOutOfRangeIsNamed) {
  ThreadDef def = StiffNylon10_0();
  def.friction_self_contacts = -1;
  try {
    def.Validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "friction_self_contacts: expected 0 (friction on objects only) to 1024");
  }
}

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(ThreadDef, ValidateMessageStartsWithTheField) {
  ThreadDef def = StiffNylon10_0();
  def.num_nodes = 1;
  try {
    def.Validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "num_nodes: expected an integer in [3, 100000]");
  }
}

TEST(ThreadDef, BadFilesNameFileLineAndField) {
  const std::string missing = ::testing::TempDir() + "/no_such_thread.yaml";
  EXPECT_EQ(ErrorOf(missing), missing + ": cannot open file");

  struct Bad {
    const char* file;
    const char* text;
    const char* error;  // after "PATH:"
  };
  const Bad cases[] = {
      {"thread_no_map.yaml", "thread: [1]\n", "1: thread: expected a map"},
      // Type errors name the field with its section.
      {"thread_bad_type.yaml", "thread:\n  base: necklace\n  diameter_m: thick\n",
       "3: thread.diameter_m: expected a number"},
      {"thread_not_finite.yaml", "thread:\n  length_m: .inf\n",
       "2: thread.length_m: expected a finite number"},
      {"thread_bad_int.yaml", "thread:\n  num_nodes: many\n",
       "2: thread.num_nodes: expected an integer"},
      {"thread_unknown.yaml", "thread:\n  name: x\n  stifness: 3\n",
       "3: thread.stifness: unknown key"},
      {"thread_bad_base.yaml", "thread:\n  base: hemp\n",
       "2: thread.base: thread preset: expected stiff-nylon-10-0, soft-silk or necklace, got "
       "'hemp'"},
      {"thread_bad_gravity.yaml", "thread:\n\n  gravity_m_per_s2: [0, 0]\n",
       "3: thread.gravity_m_per_s2: expected [x, y, z]"},
      {"thread_bad_integrator.yaml", "thread:\n  integrator: rk4\n",
       "2: thread.integrator: integrator: expected semi-implicit-euler or "
       "linearly-implicit-euler, got 'rk4'"},
      // Values that parse but fail Validate(): the line of the field.
      {"thread_invalid.yaml", "thread:\n  base: necklace\n  num_nodes: 1\n",
       "3: thread.num_nodes: expected an integer in [3, 100000]"},
      // ... and for a field left at its default, the line of its section.
      {"thread_invalid_default.yaml", "# short\nthread:\n  length_m: 0.0005\n",
       "2: thread.contact_cutoff_m: expected a positive length below the link length"},
  };
  for (const Bad& bad : cases) {
    const std::string path = Write(bad.file, bad.text);
    EXPECT_EQ(ErrorOf(path), path + ":" + bad.error);
  }
  const std::string malformed = Write("thread_malformed.yaml", "thread: {name: x\n");
  const std::string error = ErrorOf(malformed);
  EXPECT_EQ(error.rfind(malformed + ":2: malformed YAML: ", 0), 0u) << error;
}

}  // namespace
}  // namespace microdex::thread
