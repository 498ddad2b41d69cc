// GraspDef's one validation point: each bad field is named in the message, the defaults and the
// test scenes pass, and the model's mass and springs follow from the def.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/grasp/grasp_model.h"

namespace microdex::grasp {
namespace {

void ExpectField(const std::function<void(GraspDef&)>& spoil, const std::string& field) {
  GraspDef def;
  spoil(def);
  try {
    def.Validate();
    ADD_FAILURE() << "accepted a bad " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind(field + ": ", 0), 0u) << e.what();
  }
}

TEST(GraspDef, DefaultsAreValid) {
  EXPECT_NO_THROW(GraspDef{}.Validate());
  for (ShapeKind kind : {ShapeKind::kBox, ShapeKind::kCylinder, ShapeKind::kSphere}) {
    GraspDef def;
    def.shape.kind = kind;
    EXPECT_NO_THROW(def.Validate()) << ShapeKindName(kind);
  }
}

TEST(GraspDef, NamesTheBadField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ExpectField([](GraspDef& d) { d.shape.box_size_m.y() = 0.0; }, "shape.box_size_m");
  ExpectField([](GraspDef& d) { d.shape.box_size_m.x() = 1.0; }, "shape.box_size_m");
  ExpectField(
      [&](GraspDef& d) {
        d.shape.kind = ShapeKind::kSphere;
        d.shape.radius_m = nan;
      },
      "shape.radius_m");
  ExpectField(
      [](GraspDef& d) {
        d.shape.kind = ShapeKind::kCylinder;
        d.shape.length_m = -1e-3;
      },
      "shape.length_m");
  ExpectField([](GraspDef& d) { d.shape.kind = static_cast<ShapeKind>(7); }, "shape.kind");
  ExpectField([](GraspDef& d) { d.density_kg_per_m3 = 0.0; }, "density_kg_per_m3");
  ExpectField([](GraspDef& d) { d.jaw_friction = -0.1; }, "jaw_friction");
  ExpectField([&](GraspDef& d) { d.table_friction = nan; }, "table_friction");
  ExpectField([](GraspDef& d) { d.jaws.width_m = 0.0; }, "jaws.width_m");
  ExpectField([](GraspDef& d) { d.jaws.length_m = 1.0; }, "jaws.length_m");
  ExpectField([](GraspDef& d) { d.jaws.thickness_m = -1.0; }, "jaws.thickness_m");
  ExpectField([](GraspDef& d) { d.jaws.open_gap_m = -1e-3; }, "jaws.open_gap_m");
  ExpectField([](GraspDef& d) { d.jaws.closed_gap_m = 1.0; }, "jaws.closed_gap_m");
  ExpectField([](GraspDef& d) { d.contact.table_stiffness_N_per_m = 0.0; },
              "contact.table_stiffness_N_per_m");
  ExpectField([](GraspDef& d) { d.contact.jaw_stiffness_N_per_m = 1e12; },
              "contact.jaw_stiffness_N_per_m");
  ExpectField([](GraspDef& d) { d.contact.damping_ratio = -1.0; }, "contact.damping_ratio");
  ExpectField([](GraspDef& d) { d.contact.speculative_margin_m = 1.0; },
              "contact.speculative_margin_m");
  ExpectField([](GraspDef& d) { d.contact.jaw_stiffness_limit = 0.0; },
              "contact.jaw_stiffness_limit");
  ExpectField([](GraspDef& d) { d.contact.table_stiffness_limit = 0.0; },
              "contact.table_stiffness_limit");
  ExpectField([](GraspDef& d) { d.solver.iterations = 0; }, "solver.iterations");
  ExpectField([](GraspDef& d) { d.solver.substeps = 0; }, "solver.substeps");
  ExpectField([](GraspDef& d) { d.metrics.grip_weight_fraction = -1.0; },
              "metrics.grip_weight_fraction");
  ExpectField([](GraspDef& d) { d.metrics.release_time_s = 100.0; }, "metrics.release_time_s");
  ExpectField([&](GraspDef& d) { d.gravity_m_per_s2.x() = nan; }, "gravity_m_per_s2");
  ExpectField([](GraspDef& d) { d.max_time_step_s = 0.0; }, "max_time_step_s");
}

TEST(GraspModel, MakeValidatesAndDerivesMassAndSprings) {
  GraspDef bad;
  bad.density_kg_per_m3 = -1.0;
  EXPECT_THROW(MakeGraspModel(bad), std::invalid_argument);
  GraspDef def;
  def.shape.box_size_m = Eigen::Vector3d(1e-3, 2e-3, 0.5e-3);
  def.density_kg_per_m3 = 2000.0;
  const GraspModel model = MakeGraspModel(def);
  EXPECT_NEAR(model.mass_kg, 2000.0 * 1e-9, 1e-20);
  EXPECT_NEAR(model.weight_N, model.mass_kg * 9.81, 1e-18);
  // Critical damping of the object's mass on the pair's spring, times the ratio.
  EXPECT_NEAR(model.damping_N_s_per_m[kJawPlusPair],
              2.0 * def.contact.damping_ratio *
                  std::sqrt(def.contact.jaw_stiffness_N_per_m * model.mass_kg),
              1e-15);
}

}  // namespace
}  // namespace microdex::grasp
