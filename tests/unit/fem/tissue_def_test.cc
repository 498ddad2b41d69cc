// TissueDef: the YAML parameter files (assets/scenes/tissue_*.yaml) and their error messages.
#include "common/fem/tissue_def.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/fem/tissue_model.h"

namespace microdex::fem {
namespace {

std::string SourceDir() {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return dir != nullptr ? dir : ".";
}

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::string& path) {
  try {
    LoadTissueDef(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(TissueDefFile, SceneFilesLoadInSiUnits) {
  const TissueDef study = LoadTissueDef(SourceDir() + "/assets/scenes/tissue_thesis_study.yaml");
  // The thesis's study in SI: 20 cm square, G = 1 N/cm², 1 cm thick.
  EXPECT_DOUBLE_EQ(study.length_x_m, 20 * kMetrePerCm);
  EXPECT_DOUBLE_EQ(study.length_y_m, 20 * kMetrePerCm);
  EXPECT_DOUBLE_EQ(study.shear_modulus_Pa, 1 * kPascalPerNewtonPerCm2);
  EXPECT_DOUBLE_EQ(study.thickness_m, 1 * kMetrePerCm);
  EXPECT_EQ(study.level, 7);
  EXPECT_DOUBLE_EQ(study.end_resolution, 64);
  EXPECT_EQ(study.mesh, MeshKind::kMultiscale);
  EXPECT_EQ(study.solver, SolverKind::kCholmod);
  EXPECT_EQ(study.ordering, Ordering::kNestedDissection);

  const TissueDef fat = LoadTissueDef(SourceDir() + "/assets/scenes/tissue_soft_fat.yaml");
  EXPECT_DOUBLE_EQ(fat.shear_modulus_Pa, 1.0e3);
  EXPECT_EQ(fat.solver, SolverKind::kPcgIc);
  EXPECT_EQ(fat.max_contact_nodes, 2048);
  const TissueDef skin = LoadTissueDef(SourceDir() + "/assets/scenes/tissue_skin_patch.yaml");
  EXPECT_DOUBLE_EQ(skin.length_x_m, 0.02);
  EXPECT_DOUBLE_EQ(skin.thickness_m, 0.002);
  EXPECT_EQ(skin.solver, SolverKind::kPcgIc);
  EXPECT_EQ(TissueDef{}.solver, SolverKind::kPcgIc) << "the default is the station's solver";
  for (const TissueDef& def : {study, fat, skin}) EXPECT_NO_THROW(BuildTissueModel(def));
}

TEST(TissueDefFile, AbsentKeysKeepDefaults) {
  const TissueDef def = LoadTissueDef(Write("tissue_minimal.yaml", "tissue:\n  level: 5\n"));
  EXPECT_EQ(def.level, 5);
  EXPECT_EQ(def.max_level, TissueDef{}.max_level);
  EXPECT_DOUBLE_EQ(def.grading, TissueDef{}.grading);
}

TEST(TissueDefFile, BadFilesNameFileAndField) {
  const std::string missing = ::testing::TempDir() + "/no_such_tissue.yaml";
  EXPECT_NE(ErrorOf(missing).find("no_such_tissue.yaml"), std::string::npos);

  struct Bad {
    const char* file;
    const char* text;
    const char* field;
  };
  const Bad cases[] = {
      {"tissue_no_map.yaml", "tissue: 3\n", "'tissue'"},
      {"tissue_bad_type.yaml", "tissue:\n  shear_modulus_Pa: soft\n", "tissue.shear_modulus_Pa"},
      {"tissue_bad_int.yaml", "tissue:\n  level: 6.5\n", "tissue.level"},
      {"tissue_unknown.yaml", "tissue:\n  youngs_modulus_Pa: 1e4\n", "tissue.youngs_modulus_Pa"},
      {"tissue_bad_solver.yaml", "tissue:\n  solver: lu\n", "tissue.solver"},
      {"tissue_bad_mesh.yaml", "tissue:\n  mesh: coarse\n", "tissue.mesh"},
      {"tissue_bad_ordering.yaml", "tissue:\n  ordering: metis\n", "tissue.ordering"},
      {"tissue_negative_g.yaml", "tissue:\n  shear_modulus_Pa: -1\n", "shear_modulus_Pa"},
      {"tissue_level_high.yaml", "tissue:\n  max_level: 6\n  level: 7\n", "level"},
      {"tissue_end_resolution.yaml", "tissue:\n  end_resolution: -64\n", "end_resolution"},
      {"tissue_end_levels.yaml", "tissue:\n  end_levels: 9\n", "end_levels"},
      {"tissue_malformed.yaml", "tissue: [1, 2\n", "malformed"},
  };
  for (const Bad& bad : cases) {
    const std::string error = ErrorOf(Write(bad.file, bad.text));
    EXPECT_NE(error.find(bad.file), std::string::npos) << bad.file << ": " << error;
    EXPECT_NE(error.find(bad.field), std::string::npos) << bad.file << ": " << error;
  }
}

}  // namespace
}  // namespace microdex::fem
