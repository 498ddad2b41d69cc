#include "common/geometry/arc_torus_sp.h"

#include <cmath>
#include <limits>

#include "common/geometry/arc_torus_sp_ascent.h"
#include "common/geometry/arc_torus_sp_certify.h"
#include "common/geometry/arc_torus_sp_clip.h"
#include "common/geometry/arc_torus_sp_fallback.h"
#include "common/geometry/arc_torus_sp_solve.h"

// The query in the order of its stages (README_sp.md): clip the arc to the segment
// (arc_torus_sp_clip), lift the wall torus and the needle circle to S³ (arc_torus_sp_lift),
// solve for the extrema of φ (arc_torus_sp_solve), refine by the distance ascent
// (arc_torus_sp_ascent), certify against the level torus through the deepest point
// (arc_torus_sp_certify), fall back to uniform starts or to the exact method
// (arc_torus_sp_fallback).

namespace microdex::geometry {
namespace {

using namespace sp;  // the stages

// The clearance at the deepest point found, its needle point D and the wall point B nearest
// to it, in world.
ArcTorusClearance MakeResult(const NeedleInV& nv, const TorusSegmentDef& torus, const Best& best) {
  ArcTorusClearance out;
  const double core_r = torus.core_radius_m;
  const double tube_r = torus.tube_radius_m;
  const double dist = std::sqrt(best.f);
  const double clearance = tube_r - dist;
  if (!std::isfinite(clearance)) {
    // Finite input whose squares overflow: report it as invalid rather than a NaN.
    out.status = ClearanceStatus::kInvalidInput;
    out.clearance_m = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  out.status = ClearanceStatus::kOk;
  out.clearance_m = clearance;
  out.contact = clearance <= 0;
  out.s_rad = best.s;
  const Eigen::Vector3d p_VD = nv.o + nv.rho * (best.cos_s * nv.e1 + best.sin_s * nv.e2);
  out.p_WD = torus.X_WV * p_VD;
  // Nearest wall point: along the ray from the nearest core point through the needle point,
  // whose distance from it is dist (f was evaluated at this very point).
  const double w = std::sqrt(p_VD.x() * p_VD.x() + p_VD.y() * p_VD.y());
  const double inv_w = 1 / w, inv_dist = 1 / dist;
  const Eigen::Vector3d radial =
      w > 0 ? Eigen::Vector3d(p_VD.x() * inv_w, p_VD.y() * inv_w, 0) : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d core_pt = core_r * radial;
  const Eigen::Vector3d dir = dist > 0 ? Eigen::Vector3d((p_VD - core_pt) * inv_dist) : radial;
  out.p_WB = torus.X_WV * Eigen::Vector3d(core_pt + tube_r * dir);
  return out;
}

}  // namespace

const char* ToString(SpDecision decision) {
  switch (decision) {
    case SpDecision::kInvalidInput:
      return "invalid_input";
    case SpDecision::kEmptyRange:
      return "empty_range";
    case SpDecision::kThesisPass:
      return "thesis_pass";
    case SpDecision::kQuickCertificate:
      return "quick_certificate";
    case SpDecision::kLiftedCertificate:
      return "lifted_certificate";
    case SpDecision::kAlongNeedle:
      return "along_needle";
    case SpDecision::kRoundsExhausted:
      return "rounds_exhausted";
    case SpDecision::kExact:
      return "exact";
  }
  return "?";
}

ArcTorusClearance CalcArcTorusClearanceSP(const ArcDef& arc, const TorusSegmentDef& torus,
                                          const SpOptions& options) {
  return CalcArcTorusClearanceSP(arc, torus, options, nullptr);
}

ArcTorusClearance CalcArcTorusClearanceSP(const ArcDef& arc, const TorusSegmentDef& torus,
                                          const SpOptions& opt, SpDiagnostics* diagnostics) {
  SpDiagnostics local_diag;
  SpDiagnostics& diag = diagnostics != nullptr ? *diagnostics : local_diag;
  diag = SpDiagnostics{};
  ArcTorusClearance out;
  out.clearance_m = std::numeric_limits<double>::quiet_NaN();
  if (FindArcTorusInputError(arc, torus) != nullptr) {
    out.status = ClearanceStatus::kInvalidInput;
    return out;
  }
  const double core_r = torus.core_radius_m;
  const double tube_r = torus.tube_radius_m;

  // 1. Clip (§4.2.4): the pieces of the arc inside the segment.
  const NeedleInV nv = MakeNeedleInV(arc, torus);
  Interval iv[kMaxIntervals];
  double cos_sweep, sin_sweep;
  CosSin(arc.sweep_rad, &cos_sweep, &sin_sweep);
  const int n_iv =
      ClipArcToSegment(nv, arc.sweep_rad, cos_sweep, sin_sweep, torus.segment_angle_rad, iv);
  diag.num_intervals = n_iv;
  if (n_iv == 0) {
    diag.decision = SpDecision::kEmptyRange;
    out.status = ClearanceStatus::kEmptyRange;
    return out;
  }
  Candidate cand[kMaxCandidates];
  int n_cand = 0;
  const bool deep = AddPieceEnds(nv, core_r, iv, n_iv, cand, &n_cand);

  // 2–3. Lift and solve: the thesis's pass against the vessel wall. Its minima of φ with the
  // piece ends decide touch / no-touch, and they start the distance ascent. With the
  // certificate it is the level-set search's first step at t = r; starting that search at the
  // piece ends instead (t = their largest distance) gives the same certified answer with one
  // pass less when an end is the deepest point (README_sp.md), so it runs only without the
  // certificate or when asked (wall_pass_first). Diagnostics run it for the report alone
  // (sign changes, min φ): its points then do not join the search, which stays the same.
  const int rounds = opt.polish_max_iters > 0 ? opt.max_certify_rounds : 0;
  const bool wall_pass = rounds == 0 || opt.wall_pass_first;
  SpPass pass;
  if ((wall_pass && !deep) || diagnostics != nullptr) {
    RunSpPass(nv, core_r, tube_r, iv, n_iv, opt, diagnostics != nullptr,
              std::numeric_limits<double>::infinity(), &pass);
    diag.lifted_radius = pass.lifted_radius;
    diag.phi_constant = pass.phi_constant;
    diag.quartic_fallback = pass.quartic_fallback;
    diag.num_extrema = pass.n;
    if (diagnostics != nullptr && pass.ok) {
      CountSignChanges(nv, core_r, tube_r, iv, n_iv, pass, &diag);
    }
  }
  const bool have_pass = wall_pass && !deep;
  // Beyond the horn torus (t ≥ R) the level sets are spindle tori, which (4.4) cannot express:
  // there only the quick test can certify (see below), and the exact method answers when it
  // cannot, or when the search starts with the wall pass.
  if (deep && (rounds == 0 || !opt.quick_certificate || opt.wall_pass_first)) {
    return FallBackToExact(arc, torus, &diag);
  }
  if (have_pass) {
    for (int j = 0; j < pass.n; ++j) {
      if (!pass.is_min[j]) continue;
      cand[n_cand++] = MakeCandidate(nv, core_r, pass.s[j], pass.cos_s[j], pass.sin_s[j],
                                     pass.interval[j], CandidateKind::kInterior);
    }
    if (!pass.ok) {
      // 6. No usable extrema (README_sp.md, "Fallbacks"): start from uniform points instead.
      diag.fallback = true;
      AddUniformCandidates(nv, core_r, iv, n_iv, cand, &n_cand);
    }
  }

  // 4. Refine: the distance ascent.
  Best best;
  if (rounds > 0 && (!have_pass || pass.ok)) {
    // The certificate below finds any farther point, so only the most promising candidate
    // (largest distance before the ascent) is refined here.
    int j_best = 0;
    double f_best = -1;
    for (int j = 0; j < n_cand; ++j) {
      const double f = cand[j].f;
      if (f > f_best) {
        f_best = f;
        j_best = j;
      }
    }
    TryCandidate(nv, core_r, iv, cand[j_best], opt, &best);
  } else {
    for (int j = 0; j < n_cand; ++j) TryCandidate(nv, core_r, iv, cand[j], opt, &best);
  }

  // 5. Certify: the extrema of G are not those of the distance, so the ascent may have
  // stopped at a local maximum. The level set {distance = t} with t = the best distance so
  // far is itself a torus (tube radius t); a pass against it finds a point farther than t
  // wherever one exists. Repeat from such a point until none is left.
  if (IsDeep(best.f, core_r) && (rounds == 0 || !opt.quick_certificate)) {
    return FallBackToExact(arc, torus, &diag);
  }
  diag.decision = rounds == 0 ? SpDecision::kThesisPass : SpDecision::kRoundsExhausted;
  for (int round = 0; round < rounds; ++round) {
    ++diag.certify_passes;
    if (opt.quick_certificate) {
      const CertifyStep quick = QuickCertify(nv, core_r, iv, n_iv, opt, &best);
      if (quick == CertifyStep::kProved) {
        ++diag.certify_quick;
        diag.decision = SpDecision::kQuickCertificate;
        break;
      }
      if (quick == CertifyStep::kProvedAlongNeedle) {
        diag.decision = SpDecision::kAlongNeedle;
        break;
      }
      if (quick == CertifyStep::kImproved) {
        ++diag.certify_improvements;
        continue;
      }
    }
    if (IsDeep(best.f, core_r)) return FallBackToExact(arc, torus, &diag);
    ++diag.certify_lifted;
    if (LiftedCertify(nv, core_r, iv, n_iv, opt, &best, &diag.fallback) == CertifyStep::kProved) {
      diag.decision = SpDecision::kLiftedCertificate;
      break;
    }
    ++diag.certify_improvements;
  }
  return MakeResult(nv, torus, best);
}

}  // namespace microdex::geometry
