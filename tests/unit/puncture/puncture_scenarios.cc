#include "tests/unit/puncture/puncture_scenarios.h"

#include <cmath>
#include <numbers>

namespace microdex::puncture::testing {

ThroughScenario::ThroughScenario() {
  tissue.length_x_m = 0.02;
  tissue.length_y_m = 0.02;
  tissue.shear_modulus_Pa = 2e4;
  tissue.thickness_m = 2e-3;
  tissue.max_level = 8;
  tissue.level = 6;
  tissue.solver = fem::SolverKind::kPcgIc;
}

NeedleArc ThroughScenario::ArcWithTipAt(double a_tip_rad) const {
  const double a_tail = a_tip_rad - sweep_rad;
  NeedleArc arc;
  arc.c_S = centre_S;
  arc.e1_S = Eigen::Vector3d(std::cos(a_tail), 0, std::sin(a_tail));
  arc.e2_S = Eigen::Vector3d(-std::sin(a_tail), 0, std::cos(a_tail));
  arc.radius_m = radius_m;
  arc.sweep_rad = sweep_rad;
  return arc;
}

double ThroughScenario::EntryAngle() const {
  return std::numbers::pi + std::asin(centre_S.z() / radius_m);
}

double ThroughScenario::ExitAngle() const {
  return 2 * std::numbers::pi - std::asin(centre_S.z() / radius_m);
}

}  // namespace microdex::puncture::testing
