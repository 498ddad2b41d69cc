#pragma once
// The needle–vessel query by stereographic projection (SP), thesis §4.2 and appendix B.
//
// The torus is normalised (appendix B) and lifted to the quadric G = α²(l² + m²) − (p² + q²)
// on S³ (4.4); the needle's circle lifts to a circle of S³, the section of S³ by an affine
// 2-plane π (4.7)–(4.14); on π, G is a conic T (4.15), and its extrema on the lifted circle are
// the real roots of a quartic (4.26). Because sign(G) = sign(r − distance to the core circle),
// the values of φ(θ) = T on the circle (4.28) at those extrema and at the arc ends decide
// touch / no-touch exactly. The extrema of G are not those of the distance, so the clearance
// (arc_torus.h) is evaluated at SP candidates refined by a Newton ascent of the true distance,
// and certified against the level torus {distance = t} through the deepest point found, which
// is itself a torus of tube radius t: first by a quick test on the lifted torus along the
// needle, deflated at that point, and where it cannot prove, by a full SP pass; beyond the horn
// torus (t ≥ R: spindle level sets) by the quick test outside the spindle's lemon and an
// extrema search along the needle, the exact method answering where their error bound fails
// (README_sp.md).
//
// Hot path: no allocation, no virtual call, no exception. Invalid input returns kInvalidInput.

#include <Eigen/Core>
#include <cstdint>

#include "common/geometry/arc_torus.h"

namespace microdex::geometry {

enum class SpQuarticMethod {
  kClosedForm,  // Ferrari's closed form, polished by Newton steps, checked (quartic.h)
  kNewton,      // bracketed Newton iteration to quartic_tol (the thesis's §4.3 setting)
};

struct SpOptions {
  SpQuarticMethod quartic_method = SpQuarticMethod::kClosedForm;
  int closed_form_polish = 1;  // Newton steps on each closed-form root
  // End criterion of the Newton iteration on the quartic (4.26), in the unit-circle
  // coordinate u (dimensionless, ≈ radians on the lifted circle): the thesis's accuracy knob.
  double quartic_tol = 1e-15;
  int quartic_max_iters = 80;
  // Newton ascent of the distance to the core circle from the SP candidates, per candidate.
  // 0 evaluates the clearance at the extrema of G only (the thesis's "nearest point in the
  // sense of lowest G").
  int polish_max_iters = 12;
  double polish_tol_rad = 1e-8;
  // Certificate passes against the level torus through the deepest point found (README_sp.md);
  // 0 keeps the thesis's single pass. Needs the ascent: ignored when polish_max_iters = 0.
  int max_certify_rounds = 6;
  // With the certificate, run the thesis's pass against the tube wall first (as the thesis
  // does; always run when diagnostics are requested or without the certificate). Off, the
  // level-set search starts at the arc ends: the same answer, usually one pass less.
  bool wall_pass_first = false;
  // Each certificate round first tries the quick test (README_sp.md, "Certificate"): with the
  // level torus through the deepest point, the conic deflated there proves "no farther point"
  // without the quartic (4.26); the full pass runs only when it cannot. Off: always the full
  // pass (the same answer, for comparison).
  bool quick_certificate = true;
};

// The stage that settled a query (SpDiagnostics::decision; README_sp.md, "Stages").
enum class SpDecision : std::uint8_t {
  kInvalidInput,       // rejected before any stage
  kEmptyRange,         // clip: no needle point inside the segment
  kThesisPass,         // no certificate (max_certify_rounds = 0 or polish_max_iters = 0): the
                       // wall pass's minima and the piece ends, ascended if polish is on
  kQuickCertificate,   // certify: the quick test on the level torus proved no farther point
  kLiftedCertificate,  // certify: a full SP pass (lift + quartic) against the level torus
  kAlongNeedle,        // certify, beyond the horn torus: the extrema along the needle
  kRoundsExhausted,    // certify: max_certify_rounds used up while still finding farther points
  kExact,              // fall back: the exact method answered (deep contact)
};
const char* ToString(SpDecision decision);

// What the SP path did for one query (tests, benchmark, telemetry). Optional output. Asking
// for it does not change the path, except that the thesis's wall pass is also run, for the
// sign-change report alone, where the path does not run it.
struct SpDiagnostics {
  SpDecision decision = SpDecision::kInvalidInput;
  bool fallback = false;          // the lifted circle was too ill-conditioned: robust path used
  bool quartic_fallback = false;  // the closed form failed its check: bracketed search used
  bool phi_constant = false;      // φ(θ) constant on the lifted circle: no isolated extrema
  int certify_passes = 0;         // certificate rounds against level tori: the quick test,
                                  // then a lifted pass (deep: extrema along the needle)
  int certify_improvements = 0;   // of which found a farther point than the ascent had
  int certify_quick = 0;          // of which settled by the quick test (no quartic)
  int certify_lifted = 0;         // of which ran a full lifted SP pass (lift + quartic)
  int num_extrema = 0;            // critical points of φ found on the whole lifted circle
  int num_intervals = 0;          // pieces of the arc inside the segment's azimuth range
  int num_sign_changes = 0;       // sign changes of φ along the clipped arc (§4.2.4)
  double min_phi = 0;             // min of φ (4.28) over the clipped arc: > 0 ⇔ no contact
  double lifted_radius = 0;       // radius of the lifted circle in R⁴ (4.9)

  // A point ≥ R from the core circle that the quick test could not certify (or
  // wall_pass_first): the exact method answered.
  bool deep_fallback() const { return decision == SpDecision::kExact; }
};

ArcTorusClearance CalcArcTorusClearanceSP(const ArcDef& arc, const TorusSegmentDef& torus,
                                          const SpOptions& options = {});
ArcTorusClearance CalcArcTorusClearanceSP(const ArcDef& arc, const TorusSegmentDef& torus,
                                          const SpOptions& options, SpDiagnostics* diagnostics);

// ---- Building blocks, exposed for tests. -------------------------------------------------

// The lifted needle circle: centre c, radius R̂ and an orthonormal basis (b_x, b_y) of its
// plane π in R⁴ (4.8)–(4.12); b_x points at the lift of the needle's s = 0 point and b_y
// is oriented so that θ grows with the needle parameter s.
struct LiftedCircle {
  Eigen::Vector4d center = Eigen::Vector4d::Zero();
  double radius = 0;
  Eigen::Vector4d bx = Eigen::Vector4d::Zero();
  Eigen::Vector4d by = Eigen::Vector4d::Zero();
};

// The circle with centre o, unit in-plane axes e1, e2 and radius rho (x(s) = o + rho(cos s e1
// + sin s e2)), all in the normalised torus frame.
LiftedCircle CalcLiftedCircle(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                              const Eigen::Vector3d& e2, double rho);

// φ(θ) = A cos²θ + B cosθ sinθ + C sin²θ + D cosθ + E sinθ + F: the conic (4.15) on the
// lifted circle, with R̂ folded into the coefficients (A = aR̂², D = dR̂, …) (4.28).
struct CircleConic {
  double a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
  double Eval(double cos_t, double sin_t) const {
    return a * cos_t * cos_t + b * cos_t * sin_t + c * sin_t * sin_t + d * cos_t + e * sin_t + f;
  }
};
CircleConic CalcCircleConic(double alpha, const LiftedCircle& circle);

// The lifted torus along the needle, for the quick certificate (README_sp.md): in units of R,
// with x(s) = o + ρ(cos s e1 + sin s e2) and λ of appendix B for tube radius t,
// G̃(s) = (λ²|x|² + 1)² G(P⁻¹(λx)) / λ⁴ = 4t²(x² + y²) − 4(1 − t²)z² − (|x|² − 1 + t²)²,
// a trigonometric polynomial of degree 2 in s with the sign of G: positive where the needle
// point is closer than t to the core circle. It is the torus equation (4.1) arranged so that
// every term is of the size of t² near the tube (no cancellation of terms of size R⁴).
// rho_sq_minus_one = ρ² − 1 formed by the caller; *size (optional) = Σ|terms|, the scale of
// the coefficients' rounding; *axis_dist_sq_min (optional) = a lower bound of x² + y² on the
// whole needle circle (possibly ≤ 0).
CircleConic CalcLevelTorusAlongNeedle(const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                                      const Eigen::Vector3d& e2, double rho,
                                      double rho_sq_minus_one, double t_sq, double* size,
                                      double* axis_dist_sq_min = nullptr);

// The rotation ψ of (4.19)–(4.21) that removes the u² − v² term of φ'(θ) = 0 (4.17)–(4.18),
// and the coefficients of the rotated condition β uv + γ u + δ v = 0 (4.23).
struct ExtremaCondition {
  double cos_psi = 1, sin_psi = 0;
  double beta = 0, gamma = 0, delta = 0;
};
ExtremaCondition CalcExtremaCondition(const CircleConic& conic);

// Up to 4 extrema of φ on the unit circle as (cos θ, sin θ) from the quartic (4.26); returns
// their count. Candidates that the quartic cannot separate (both signs of v) are all kept.
int FindConicExtremaOnCircle(const CircleConic& conic, const SpOptions& options, double cos_t[8],
                             double sin_t[8], bool* phi_constant);
int FindConicExtremaOnCircle(const CircleConic& conic, const SpOptions& options, double cos_t[8],
                             double sin_t[8], bool* phi_constant, bool* quartic_fallback);

}  // namespace microdex::geometry
