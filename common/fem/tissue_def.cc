#include "common/fem/tissue_def.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "common/base/yaml_field.h"

namespace microdex::fem {
namespace {

void Require(bool ok, const char* field, const std::string& expected) {
  if (!ok)
    throw std::invalid_argument(std::string("TissueDef.") + field + ": expected " + expected);
}

}  // namespace

const char* ToString(MeshKind kind) { return kind == MeshKind::kFine ? "fine" : "multiscale"; }

const char* ToString(SolverKind kind) {
  switch (kind) {
    case SolverKind::kCg:
      return "cg";
    case SolverKind::kPcgJacobi:
      return "pcg_jacobi";
    case SolverKind::kPcgIc:
      return "pcg_ic";
    case SolverKind::kCholmod:
      return "cholmod";
  }
  return "?";
}

const char* ToString(Ordering ordering) {
  return ordering == Ordering::kAmd ? "amd" : "nested_dissection";
}

MeshKind ParseMeshKind(const std::string& text) {
  if (text == "fine") return MeshKind::kFine;
  if (text == "multiscale") return MeshKind::kMultiscale;
  throw std::invalid_argument("mesh kind '" + text + "': expected fine or multiscale");
}

SolverKind ParseSolverKind(const std::string& text) {
  for (SolverKind kind :
       {SolverKind::kCg, SolverKind::kPcgJacobi, SolverKind::kPcgIc, SolverKind::kCholmod}) {
    if (text == ToString(kind)) return kind;
  }
  throw std::invalid_argument("solver '" + text + "': expected cg, pcg_jacobi, pcg_ic or cholmod");
}

Ordering ParseOrdering(const std::string& text) {
  if (text == "nested_dissection") return Ordering::kNestedDissection;
  if (text == "amd") return Ordering::kAmd;
  throw std::invalid_argument("ordering '" + text + "': expected nested_dissection or amd");
}

void TissueDef::Validate() const {
  Require(std::isfinite(length_x_m) && length_x_m > 0, "length_x_m", "a positive length in m");
  Require(std::isfinite(length_y_m) && length_y_m > 0, "length_y_m", "a positive length in m");
  Require(std::isfinite(shear_modulus_Pa) && shear_modulus_Pa > 0, "shear_modulus_Pa",
          "a positive modulus in Pa");
  Require(std::isfinite(thickness_m) && thickness_m > 0, "thickness_m", "a positive length in m");
  Require(max_level >= 1 && max_level <= 10, "max_level", "an integer in [1, 10]");
  Require(level >= 1 && level <= max_level, "level", "an integer in [1, max_level]");
  Require(std::isfinite(grading) && grading >= 1.5 && grading <= 64, "grading",
          "a value in [1.5, 64] (below 1.5 neighbouring leaves may differ by two levels)");
  Require(std::isfinite(end_resolution) && end_resolution >= 0 && end_resolution <= 1e4,
          "end_resolution", "0 (off) or end-zone cells per tool length in (0, 1e4]");
  Require(end_levels >= 0 && end_levels <= 6, "end_levels", "an integer in [0, 6]");
  Require(std::isfinite(cg_relative_tolerance) && cg_relative_tolerance > 0 &&
              cg_relative_tolerance < 1,
          "cg_relative_tolerance", "a value in (0, 1)");
  Require(cg_max_iterations >= 1, "cg_max_iterations", "a positive count");
  Require(max_contact_nodes >= 1, "max_contact_nodes", "a positive count");
  Require(pattern_cache_entries >= 1 && pattern_cache_entries <= 16, "pattern_cache_entries",
          "an integer in [1, 16]");
}

namespace {

// Reads an optional enumerated field through its parser.
template <typename E>
void ReadEnum(const YAML::Node& root, const std::string& path, const char* field,
              E (*parse)(const std::string&), E& out) {
  std::string text;
  ReadYamlField(root, path, "tissue.", field, text);
  if (text.empty()) return;
  try {
    out = parse(text);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": field 'tissue." + field + "': " + e.what());
  }
}

}  // namespace

TissueDef LoadTissueDef(const std::string& path) {
  YAML::Node file;
  try {
    file = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot open tissue parameter file");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": malformed YAML: " + e.what());
  }
  const YAML::Node root = file["tissue"];
  if (!root || !root.IsMap())
    throw std::runtime_error(path + ": field 'tissue': expected a map of tissue parameters");
  static constexpr const char* kKnown[] = {"name",
                                           "length_x_m",
                                           "length_y_m",
                                           "shear_modulus_Pa",
                                           "thickness_m",
                                           "max_level",
                                           "level",
                                           "mesh",
                                           "grading",
                                           "end_resolution",
                                           "end_levels",
                                           "solver",
                                           "ordering",
                                           "cg_relative_tolerance",
                                           "cg_max_iterations",
                                           "max_contact_nodes",
                                           "pattern_cache_entries"};
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    bool known = false;
    for (const char* name : kKnown) known = known || key == name;
    if (!known)
      throw std::runtime_error(
          std::string(path).append(": field 'tissue.").append(key).append("': unknown field"));
  }
  TissueDef def;
  std::string name;  // documentation only
  ReadYamlField(root, path, "tissue.", "name", name);
  ReadYamlField(root, path, "tissue.", "length_x_m", def.length_x_m);
  ReadYamlField(root, path, "tissue.", "length_y_m", def.length_y_m);
  ReadYamlField(root, path, "tissue.", "shear_modulus_Pa", def.shear_modulus_Pa);
  ReadYamlField(root, path, "tissue.", "thickness_m", def.thickness_m);
  ReadYamlField(root, path, "tissue.", "max_level", def.max_level);
  ReadYamlField(root, path, "tissue.", "level", def.level);
  ReadEnum(root, path, "mesh", &ParseMeshKind, def.mesh);
  ReadYamlField(root, path, "tissue.", "grading", def.grading);
  ReadYamlField(root, path, "tissue.", "end_resolution", def.end_resolution);
  ReadYamlField(root, path, "tissue.", "end_levels", def.end_levels);
  ReadEnum(root, path, "solver", &ParseSolverKind, def.solver);
  ReadEnum(root, path, "ordering", &ParseOrdering, def.ordering);
  ReadYamlField(root, path, "tissue.", "cg_relative_tolerance", def.cg_relative_tolerance);
  ReadYamlField(root, path, "tissue.", "cg_max_iterations", def.cg_max_iterations);
  ReadYamlField(root, path, "tissue.", "max_contact_nodes", def.max_contact_nodes);
  ReadYamlField(root, path, "tissue.", "pattern_cache_entries", def.pattern_cache_entries);
  try {
    def.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return def;
}

}  // namespace microdex::fem
