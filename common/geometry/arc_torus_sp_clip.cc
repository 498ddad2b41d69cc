#include "common/geometry/arc_torus_sp_clip.h"

#include <cmath>

namespace microdex::geometry::sp {

NeedleInV MakeNeedleInV(const ArcDef& arc, const TorusSegmentDef& torus) {
  const Eigen::Matrix3d R_VW = torus.X_WV.linear().transpose();
  NeedleInV nv;
  nv.o = R_VW * (arc.X_WN.translation() - torus.X_WV.translation());
  // Gram–Schmidt against the unnormalised first axis, so that both normalisations run side by
  // side.
  const Eigen::Vector3d a1 = R_VW * arc.X_WN.linear().col(0);
  const Eigen::Vector3d a2 = R_VW * arc.X_WN.linear().col(1);
  const double a1_sq = a1.squaredNorm();
  nv.e1 = a1 * (1 / std::sqrt(a1_sq));
  nv.e2 = a2 - (a2.dot(a1) / a1_sq) * a1;
  nv.e2 *= 1 / nv.e2.norm();
  nv.e3 = nv.e1.cross(nv.e2);
  nv.rho = arc.radius_m;
  nv.inv_rho = 1 / arc.radius_m;
  return nv;
}

void CosSin(double s, double* cs, double* sn) {
  if (s == 0) {
    *cs = 1;
    *sn = 0;
    return;
  }
  *cs = std::cos(s);
  *sn = std::sin(s);
}

int FindInterval(const Interval* iv, int n, double s) {
  for (int i = 0; i < n; ++i) {
    if (s >= iv[i].lo && s <= iv[i].hi) return i;
  }
  // Just past an end of a piece by rounding (or s ≈ 2π for a closed needle): snap.
  constexpr double kSnap_rad = 1e-12;
  for (int i = 0; i < n; ++i) {
    if (s >= iv[i].lo - kSnap_rad && s <= iv[i].hi + kSnap_rad) return i;
    if (s - kTwoPi >= iv[i].lo - kSnap_rad && s - kTwoPi <= iv[i].hi + kSnap_rad) return i;
  }
  return -1;
}

}  // namespace microdex::geometry::sp
