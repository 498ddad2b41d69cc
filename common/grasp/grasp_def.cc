#include "common/grasp/grasp_def.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace microdex::grasp {
namespace {

void Require(bool ok, const char* field, const std::string& expected) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": expected " + expected);
}

bool InRange(double value, double lo, double hi) {
  return std::isfinite(value) && value >= lo && value <= hi;
}

constexpr double kMinSize_m = 1e-5;
constexpr double kMaxSize_m = 0.05;

}  // namespace

const char* ShapeKindName(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kBox:
      return "box";
    case ShapeKind::kCylinder:
      return "cylinder";
    case ShapeKind::kSphere:
      return "sphere";
  }
  return "unknown";
}

void GraspDef::Validate() const {
  const char* size_range = "a length in [1e-5, 0.05] m";
  switch (shape.kind) {
    case ShapeKind::kBox:
      for (int i = 0; i < 3; ++i) {
        Require(InRange(shape.box_size_m[i], kMinSize_m, kMaxSize_m), "shape.box_size_m",
                std::string("edge lengths in [1e-5, 0.05] m"));
      }
      break;
    case ShapeKind::kCylinder:
      Require(InRange(shape.radius_m, kMinSize_m, kMaxSize_m), "shape.radius_m", size_range);
      Require(InRange(shape.length_m, kMinSize_m, kMaxSize_m), "shape.length_m", size_range);
      break;
    case ShapeKind::kSphere:
      Require(InRange(shape.radius_m, kMinSize_m, kMaxSize_m), "shape.radius_m", size_range);
      break;
    default:
      Require(false, "shape.kind", "box, cylinder or sphere");
  }
  Require(InRange(density_kg_per_m3, 1.0, 1e5), "density_kg_per_m3",
          "a density in [1, 1e5] kg/m^3");
  Require(InRange(jaw_friction, 0.0, 10.0), "jaw_friction", "a coefficient in [0, 10]");
  Require(InRange(table_friction, 0.0, 10.0), "table_friction", "a coefficient in [0, 10]");
  Require(InRange(jaws.width_m, kMinSize_m, kMaxSize_m), "jaws.width_m", size_range);
  Require(InRange(jaws.length_m, kMinSize_m, kMaxSize_m), "jaws.length_m", size_range);
  Require(InRange(jaws.thickness_m, kMinSize_m, kMaxSize_m), "jaws.thickness_m", size_range);
  Require(InRange(jaws.open_gap_m, 0.0, 0.1), "jaws.open_gap_m", "a gap in [0, 0.1] m");
  Require(InRange(jaws.closed_gap_m, -0.1, jaws.open_gap_m), "jaws.closed_gap_m",
          "a gap in [-0.1 m, open_gap_m]");
  Require(InRange(contact.table_stiffness_N_per_m, 1e-3, 1e9), "contact.table_stiffness_N_per_m",
          "a stiffness in [1e-3, 1e9] N/m");
  Require(InRange(contact.jaw_stiffness_N_per_m, 1e-3, 1e9), "contact.jaw_stiffness_N_per_m",
          "a stiffness in [1e-3, 1e9] N/m");
  Require(InRange(contact.damping_ratio, 0.0, 100.0), "contact.damping_ratio",
          "a ratio in [0, 100]");
  Require(InRange(contact.speculative_margin_m, 0.0, 0.01), "contact.speculative_margin_m",
          "a length in [0, 0.01] m");
  Require(InRange(contact.jaw_stiffness_limit, 1e-3, 1e12), "contact.jaw_stiffness_limit",
          "a ratio in [1e-3, 1e12]");
  Require(InRange(contact.table_stiffness_limit, 1e-3, 1e12), "contact.table_stiffness_limit",
          "a ratio in [1e-3, 1e12]");
  Require(solver.iterations >= 1 && solver.iterations <= 1000, "solver.iterations",
          "an integer in [1, 1000]");
  Require(solver.substeps >= 1 && solver.substeps <= 100, "solver.substeps",
          "an integer in [1, 100]");
  Require(InRange(metrics.grip_weight_fraction, 0.0, 1e6), "metrics.grip_weight_fraction",
          "a non-negative fraction");
  Require(InRange(metrics.release_time_s, 0.0, 10.0), "metrics.release_time_s",
          "a time in [0, 10] s");
  Require(gravity_m_per_s2.allFinite() && gravity_m_per_s2.norm() < 1e3, "gravity_m_per_s2",
          "a finite acceleration below 1000 m/s^2");
  Require(InRange(max_time_step_s, 1e-6, 0.1), "max_time_step_s", "a time step in [1e-6, 0.1] s");
}

}  // namespace microdex::grasp
