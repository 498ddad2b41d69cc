#pragma once
// SP stage 3, solve (thesis §4.2.2–§4.2.4): the extrema of φ on the lifted circle, the real
// roots of the quartic (4.26), mapped back to the needle and kept where they lie on the
// clipped arc: one SP pass. Internal to the SP clearance (arc_torus_sp.cc); exposed for its
// stage tests. (CalcExtremaCondition and FindConicExtremaOnCircle, declared in
// arc_torus_sp.h, are defined with this stage.)

#include "common/geometry/arc_torus_sp.h"
#include "common/geometry/arc_torus_sp_clip.h"
#include "common/geometry/arc_torus_sp_lift.h"

namespace microdex::geometry::sp {

// One SP pass (§4.2.2–§4.2.4) against the torus of core radius R and tube radius t: the
// minima of φ(θ) that lie on the clipped arc, as needle parameters. With `all` set, the
// maxima are kept too (for the sign-change count).
struct SpPass {
  bool ok = false;  // false: lifted circle unusable or φ constant (see diag flags)
  bool lift_ok = false;
  bool phi_constant = false;
  bool quartic_fallback = false;
  double lifted_radius = 0;
  double phi_size = 0;  // |A| + … + |F|: the scale of φ's values and of their rounding
  int n = 0;
  double s[8], cos_s[8], sin_s[8], phi[8];
  bool is_min[8];
  int interval[8];
};

// The extrema part of the pass on an already lifted conic. With phi_below finite, only the
// minima with φ < phi_below·|φ|'s size are kept (and mapped back to the needle), the others
// cost nothing more. With `all` set, the maxima are kept too (for the sign-change count).
void RunSpPassOnConic(const NeedleInV& nv, const LiftedConic& k, const Interval* iv, int n_iv,
                      const SpOptions& opt, bool all, double phi_below, SpPass* out);

// Lift (stage 2) and solve against the torus of core radius R = core_r and tube radius t.
void RunSpPass(const NeedleInV& nv, double core_r, double tube_t, const Interval* iv, int n_iv,
               const SpOptions& opt, bool all, double phi_below, SpPass* out);

// §4.2.4: sign changes of φ along each piece (ends and interior extrema in order of s), and
// the minimum of φ, for the diagnostics.
void CountSignChanges(const NeedleInV& nv, double core_r, double tube_r, const Interval* iv,
                      int n_iv, const SpPass& pass, SpDiagnostics* diag);

}  // namespace microdex::geometry::sp
