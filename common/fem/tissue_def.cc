#include "common/fem/tissue_def.h"

#include <cmath>
#include <stdexcept>

#include "common/base/yaml_reader.h"

namespace microdex::fem {
namespace {

void Require(bool ok, const char* field, const std::string& expected) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": expected " + expected);
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
    case SolverKind::kPcgDic:
      return "pcg_dic";
    case SolverKind::kCholmod:
      return "cholmod";
  }
  return "?";
}

const char* ToString(Ordering ordering) {
  return ordering == Ordering::kAmd ? "amd" : "nested_dissection";
}

const char* ToString(ToolConstraint constraint) {
  return constraint == ToolConstraint::kNearestNodes ? "nearest_nodes" : "penalty_points";
}

ToolConstraint ParseToolConstraint(const std::string& text) {
  if (text == "penalty_points") return ToolConstraint::kPenaltyPoints;
  if (text == "nearest_nodes") return ToolConstraint::kNearestNodes;
  throw std::invalid_argument("tool constraint '" + text +
                              "': expected penalty_points or nearest_nodes");
}

MeshKind ParseMeshKind(const std::string& text) {
  if (text == "fine") return MeshKind::kFine;
  if (text == "multiscale") return MeshKind::kMultiscale;
  throw std::invalid_argument("mesh kind '" + text + "': expected fine or multiscale");
}

SolverKind ParseSolverKind(const std::string& text) {
  for (SolverKind kind : {SolverKind::kCg, SolverKind::kPcgJacobi, SolverKind::kPcgIc,
                          SolverKind::kPcgDic, SolverKind::kCholmod}) {
    if (text == ToString(kind)) return kind;
  }
  throw std::invalid_argument("solver '" + text +
                              "': expected cg, pcg_jacobi, pcg_ic, pcg_dic or cholmod");
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
  Require(std::isfinite(poisson_ratio) && poisson_ratio >= 0 && poisson_ratio <= 0.5,
          "poisson_ratio", "a ratio in [0, 0.5]");
  Require(max_level >= 1 && max_level <= 10, "max_level", "an integer in [1, 10]");
  Require(level >= 1 && level <= max_level, "level", "an integer in [1, max_level]");
  Require(std::isfinite(grading) && grading >= 1.5 && grading <= 64, "grading",
          "a value in [1.5, 64] (below 1.5 neighbouring leaves may differ by two levels)");
  Require(std::isfinite(end_resolution) && end_resolution >= 0 && end_resolution <= 1e4,
          "end_resolution", "0 (off) or end-zone cells per tool length in (0, 1e4]");
  Require(end_levels >= 0 && end_levels <= 6, "end_levels", "an integer in [0, 6]");
  Require(std::isfinite(edge_resolution) && edge_resolution >= 0 && edge_resolution <= 16,
          "edge_resolution", "0 (off) or cells between the tool and an edge in (0, 16]");
  Require(edge_levels >= 0 && edge_levels <= 6, "edge_levels", "an integer in [0, 6]");
  Require(edge_max_leaves >= 0 && edge_max_leaves <= (1 << 20), "edge_max_leaves",
          "a count of leaves in [0, 2^20]");
  Require(std::isfinite(tool_kink_factor) && tool_kink_factor >= 0.25 && tool_kink_factor <= 4,
          "tool_kink_factor", "a factor in [0.25, 4]");
  Require(std::isfinite(tool_penalty) && tool_penalty >= 1 && tool_penalty <= 1e8, "tool_penalty",
          "a spring in units of G·t in [1, 1e8]");
  Require(std::isfinite(tool_point_spacing) && tool_point_spacing >= 0.1 && tool_point_spacing <= 4,
          "tool_point_spacing", "a spacing in cells in [0.1, 4]");
  Require(std::isfinite(cg_relative_tolerance) && cg_relative_tolerance > 0 &&
              cg_relative_tolerance < 1,
          "cg_relative_tolerance", "a value in (0, 1)");
  Require(std::isfinite(dic_relaxation) && dic_relaxation >= 0.5 && dic_relaxation <= 1,
          "dic_relaxation", "a factor in [0.5, 1]");
  Require(cg_max_iterations >= 1, "cg_max_iterations", "a positive count");
  Require(reattach_blend_steps >= 0 && reattach_blend_steps <= 10000, "reattach_blend_steps",
          "a count of steps in [0, 10000]");
  Require(max_contact_nodes >= 1, "max_contact_nodes", "a positive count");
  Require(pattern_cache_entries >= 1 && pattern_cache_entries <= 16, "pattern_cache_entries",
          "an integer in [1, 16]");
}

namespace {

// An enumerated field; an empty text keeps the default.
template <typename E>
E ReadEnum(const YamlSection& tissue, const char* key, E (*parse)(const std::string&), E fallback) {
  if (tissue.String(key, "").empty()) return fallback;
  return tissue.Enum(key, parse, fallback);
}

}  // namespace

TissueDef LoadTissueDef(const std::string& path) {
  const YamlSection tissue = YamlReader(path).Root().Map("tissue");
  tissue.CheckNoUnknownKeys({"name",
                             "length_x_m",
                             "length_y_m",
                             "shear_modulus_Pa",
                             "thickness_m",
                             "poisson_ratio",
                             "max_level",
                             "level",
                             "mesh",
                             "grading",
                             "end_resolution",
                             "end_levels",
                             "edge_resolution",
                             "edge_levels",
                             "edge_max_leaves",
                             "tool_constraint",
                             "tool_kink_factor",
                             "tool_penalty",
                             "tool_point_spacing",
                             "solver",
                             "ordering",
                             "cg_relative_tolerance",
                             "dic_relaxation",
                             "cg_max_iterations",
                             "attached_mesh",
                             "reattach_blend_steps",
                             "max_contact_nodes",
                             "pattern_cache_entries"});
  TissueDef def;
  (void)tissue.String("name", "");  // documentation only
  def.length_x_m = tissue.FiniteDouble("length_x_m", def.length_x_m);
  def.length_y_m = tissue.FiniteDouble("length_y_m", def.length_y_m);
  def.shear_modulus_Pa = tissue.FiniteDouble("shear_modulus_Pa", def.shear_modulus_Pa);
  def.thickness_m = tissue.FiniteDouble("thickness_m", def.thickness_m);
  def.poisson_ratio = tissue.FiniteDouble("poisson_ratio", def.poisson_ratio);
  def.max_level = tissue.Int("max_level", def.max_level);
  def.level = tissue.Int("level", def.level);
  def.mesh = ReadEnum(tissue, "mesh", &ParseMeshKind, def.mesh);
  def.grading = tissue.FiniteDouble("grading", def.grading);
  def.end_resolution = tissue.FiniteDouble("end_resolution", def.end_resolution);
  def.end_levels = tissue.Int("end_levels", def.end_levels);
  def.edge_resolution = tissue.FiniteDouble("edge_resolution", def.edge_resolution);
  def.edge_levels = tissue.Int("edge_levels", def.edge_levels);
  def.edge_max_leaves = tissue.Int("edge_max_leaves", def.edge_max_leaves);
  def.tool_constraint =
      ReadEnum(tissue, "tool_constraint", &ParseToolConstraint, def.tool_constraint);
  def.tool_kink_factor = tissue.FiniteDouble("tool_kink_factor", def.tool_kink_factor);
  def.tool_penalty = tissue.FiniteDouble("tool_penalty", def.tool_penalty);
  def.tool_point_spacing = tissue.FiniteDouble("tool_point_spacing", def.tool_point_spacing);
  def.solver = ReadEnum(tissue, "solver", &ParseSolverKind, def.solver);
  def.ordering = ReadEnum(tissue, "ordering", &ParseOrdering, def.ordering);
  def.cg_relative_tolerance =
      tissue.FiniteDouble("cg_relative_tolerance", def.cg_relative_tolerance);
  def.dic_relaxation = tissue.FiniteDouble("dic_relaxation", def.dic_relaxation);
  def.cg_max_iterations = tissue.Int("cg_max_iterations", def.cg_max_iterations);
  def.attached_mesh = tissue.Bool("attached_mesh", def.attached_mesh);
  def.reattach_blend_steps = tissue.Int("reattach_blend_steps", def.reattach_blend_steps);
  def.max_contact_nodes = tissue.Int("max_contact_nodes", def.max_contact_nodes);
  def.pattern_cache_entries = tissue.Int("pattern_cache_entries", def.pattern_cache_entries);
  try {
    def.Validate();
  } catch (const std::invalid_argument& e) {
    tissue.FailInvalid(e);
  }
  return def;
}

}  // namespace microdex::fem
