#include "common/geometry/arc_torus_sp_fallback.h"

#include <cmath>

#include "common/geometry/arc_torus_exact.h"

namespace microdex::geometry::sp {

void AddUniformCandidates(const NeedleInV& nv, double core_r, const Interval* iv, int n_iv,
                          Candidate* cand, int* n_cand) {
  for (int i = 0; i < n_iv; ++i) {
    for (int j = 1; j <= kRobustSamples; ++j) {
      const double s = iv[i].lo + (iv[i].hi - iv[i].lo) * j / (kRobustSamples + 1);
      cand[(*n_cand)++] =
          MakeCandidate(nv, core_r, s, std::cos(s), std::sin(s), i, CandidateKind::kInterior);
    }
  }
}

ArcTorusClearance FallBackToExact(const ArcDef& arc, const TorusSegmentDef& torus,
                                  SpDiagnostics* diag) {
  diag->decision = SpDecision::kExact;
  return CalcArcTorusClearanceExact(arc, torus);
}

}  // namespace microdex::geometry::sp
