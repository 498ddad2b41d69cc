#include "common/fem/tissue_def.h"

#include <cmath>
#include <stdexcept>

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
  Require(std::isfinite(cg_relative_tolerance) && cg_relative_tolerance > 0 &&
              cg_relative_tolerance < 1,
          "cg_relative_tolerance", "a value in (0, 1)");
  Require(cg_max_iterations >= 1, "cg_max_iterations", "a positive count");
  Require(max_contact_nodes >= 1, "max_contact_nodes", "a positive count");
  Require(pattern_cache_entries >= 1 && pattern_cache_entries <= 16, "pattern_cache_entries",
          "an integer in [1, 16]");
}

}  // namespace microdex::fem
