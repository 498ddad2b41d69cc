// TissueDef: the YAML parameter files (assets/scenes/tissue_*.yaml) and their error messages.
#include "common/fem/tissue_def.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/base/input_error.h"
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
  EXPECT_EQ(fat.solver, SolverKind::kPcgDic);
  EXPECT_EQ(fat.max_contact_nodes, 2048);
  const TissueDef skin = LoadTissueDef(SourceDir() + "/assets/scenes/tissue_skin_patch.yaml");
  EXPECT_DOUBLE_EQ(skin.length_x_m, 0.02);
  EXPECT_DOUBLE_EQ(skin.thickness_m, 0.002);
  EXPECT_EQ(skin.solver, SolverKind::kPcgDic);
  EXPECT_EQ(TissueDef{}.solver, SolverKind::kPcgDic) << "the default is the station's solver";
  for (const TissueDef& def : {study, fat, skin}) EXPECT_NO_THROW(BuildTissueModel(def));
}

TEST(TissueDefFile, AbsentKeysKeepDefaults) {
  const TissueDef def = LoadTissueDef(Write("tissue_minimal.yaml", "tissue:\n  level: 5\n"));
  EXPECT_EQ(def.level, 5);
  EXPECT_EQ(def.max_level, TissueDef{}.max_level);
  EXPECT_DOUBLE_EQ(def.grading, TissueDef{}.grading);
}

TEST(TissueDefFile, BadFilesNameFileLineAndField) {
  const std::string missing = ::testing::TempDir() + "/no_such_tissue.yaml";
  EXPECT_EQ(ErrorOf(missing), missing + ": cannot open file");

  struct Bad {
    const char* file;
    const char* text;
    const char* error;  // after "PATH:"
  };
  const Bad cases[] = {
      {"tissue_no_map.yaml", "tissue: 3\n", "1: tissue: expected a map"},
      {"tissue_no_section.yaml", "# tissue\nlevel: 3\n", "2: tissue: missing"},
      {"tissue_bad_type.yaml", "tissue:\n  shear_modulus_Pa: soft\n",
       "2: tissue.shear_modulus_Pa: expected a number"},
      {"tissue_not_finite.yaml", "tissue:\n  level: 5\n  shear_modulus_Pa: .nan\n",
       "3: tissue.shear_modulus_Pa: expected a finite number"},
      {"tissue_bad_int.yaml", "tissue:\n  level: 6.5\n", "2: tissue.level: expected an integer"},
      {"tissue_unknown.yaml", "tissue:\n  level: 5\n  youngs_modulus_Pa: 1e4\n",
       "3: tissue.youngs_modulus_Pa: unknown key"},
      {"tissue_bad_solver.yaml", "tissue:\n  solver: lu\n",
       "2: tissue.solver: solver 'lu': expected cg, pcg_jacobi, pcg_ic, pcg_dic or cholmod"},
      {"tissue_bad_mesh.yaml", "tissue:\n  mesh: coarse\n",
       "2: tissue.mesh: mesh kind 'coarse': expected fine or multiscale"},
      {"tissue_bad_ordering.yaml", "tissue:\n  ordering: metis\n",
       "2: tissue.ordering: ordering 'metis': expected nested_dissection or amd"},
      // Values that parse but fail Validate(): the line of the field.
      {"tissue_negative_g.yaml", "tissue:\n  level: 5\n\n  shear_modulus_Pa: -1\n",
       "4: tissue.shear_modulus_Pa: expected a positive modulus in Pa"},
      {"tissue_level_high.yaml", "tissue:\n  max_level: 6\n  level: 7\n",
       "3: tissue.level: expected an integer in [1, max_level]"},
      // ... and for a field left at its default, the line of its section.
      {"tissue_default_level_high.yaml", "\ntissue:\n  max_level: 6\n",
       "2: tissue.level: expected an integer in [1, max_level]"},
      {"tissue_end_resolution.yaml", "tissue:\n  end_resolution: -64\n",
       "2: tissue.end_resolution: expected 0 (off) or end-zone cells per tool length in (0, 1e4]"},
      {"tissue_end_levels.yaml", "tissue:\n  end_levels: 9\n",
       "2: tissue.end_levels: expected an integer in [0, 6]"},
      {"tissue_dic_relaxation.yaml", "tissue:\n  solver: pcg_dic\n  dic_relaxation: 0.3\n",
       "3: tissue.dic_relaxation: expected a factor in [0.5, 1]"},
  };
  for (const Bad& bad : cases) {
    const std::string path = Write(bad.file, bad.text);
    EXPECT_EQ(ErrorOf(path), path + ":" + bad.error);
  }
  const std::string malformed = Write("tissue_malformed.yaml", "tissue:\n  level: [1, 2\n");
  const std::string error = ErrorOf(malformed);
  EXPECT_EQ(error.rfind(malformed + ":3: malformed YAML: ", 0), 0u) << error;
}

TEST(TissueDefFile, ErrorsAreInputErrors) {
  EXPECT_THROW(LoadTissueDef(Write("tissue_input_error.yaml", "tissue:\n  level: x\n")),
               InputError);
}

}  // namespace
}  // namespace microdex::fem
