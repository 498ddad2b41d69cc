#pragma once
// The needle-through-tissue scenario shared by the puncture tests and `microdex-bench
// puncture`: a 2 × 2 cm skin-like membrane and a 3/8-circle needle of 3 mm radius in the
// vertical plane y = 10 mm, its centre 2.2 mm above the membrane, turned about its own axis so
// that the tip goes in at the entry crossing and comes out at the exit crossing.

#include "common/fem/tissue_def.h"
#include "common/puncture/puncture.h"

namespace microdex::puncture::testing {

struct ThroughScenario {
  fem::TissueDef tissue;
  PunctureDef def;
  Eigen::Vector3d centre_S{10e-3, 10e-3, 2.2e-3};
  double radius_m = 3e-3;
  double sweep_rad = 2.356194490192345;
  ThroughScenario();
  // The needle with its tip at angle a (in the x–z plane about the centre, from +x towards +z).
  NeedleArc ArcWithTipAt(double a_tip_rad) const;
  // The tip's angles where the circle crosses the rest plane: going in, coming out.
  double EntryAngle() const;
  double ExitAngle() const;
};

}  // namespace microdex::puncture::testing
