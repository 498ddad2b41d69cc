#include "common/geometry/arc_torus_sp_solve.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/geometry/quartic.h"
#include "common/geometry/stereographic.h"

namespace microdex::geometry {
namespace {

// φ'(θ) below this fraction of |φ|'s size is rounding noise: φ is constant on the circle.
constexpr double kPhiConstantRel = 1e-12;
// When the v of a quartic root cannot be told from −v (βu + δ ≈ 0 or v ≈ 0), keep both.
constexpr double kKeepBothResidual = 1e-6;

}  // namespace

ExtremaCondition CalcExtremaCondition(const CircleConic& k) {
  // (4.17) on the unit circle: φ'(θ) = B(x² − y²) + 2g xy + E x − D y with g = C − A.
  // (4.19)–(4.20): rotating by ψ turns B(x² − y²) + 2g xy into
  // (u² − v²)(B cos 2ψ + g sin 2ψ) + 2uv(g cos 2ψ − B sin 2ψ). (4.21) as printed sets
  // tan 2ψ = −b/d; the u² − v² term vanishes for tan 2ψ = −B/g, which is used here (checked
  // in arc_torus_sp_test.cc). Then β = 2(g cos 2ψ − B sin 2ψ) = 2√(B² + g²) (4.22), and the
  // linear part E x − D y becomes γ u + δ v with γ = E cos ψ − D sin ψ and
  // δ = −(E sin ψ + D cos ψ) (the printed (4.23) swaps these and drops a sign).
  ExtremaCondition x;
  const double g = k.c - k.a;
  const double n = std::sqrt(k.b * k.b + g * g);
  double c2 = 1, s2 = 0;
  if (n > 0) {
    c2 = g / n;
    s2 = -k.b / n;
  }
  // Half angle of (c2, s2) = (cos 2ψ, sin 2ψ) without trigonometry, stable on both branches.
  if (c2 >= 0) {
    x.cos_psi = std::sqrt(0.5 * (1 + c2));
    x.sin_psi = s2 / (2 * x.cos_psi);
  } else {
    x.sin_psi = std::sqrt(0.5 * (1 - c2));
    if (s2 < 0) x.sin_psi = -x.sin_psi;
    x.cos_psi = s2 / (2 * x.sin_psi);
  }
  x.beta = 2 * n;
  x.gamma = k.e * x.cos_psi - k.d * x.sin_psi;
  x.delta = -(k.e * x.sin_psi + k.d * x.cos_psi);
  return x;
}

int FindConicExtremaOnCircle(const CircleConic& k, const SpOptions& opt, double cos_t[8],
                             double sin_t[8], bool* phi_constant) {
  bool unused;
  return FindConicExtremaOnCircle(k, opt, cos_t, sin_t, phi_constant, &unused);
}

int FindConicExtremaOnCircle(const CircleConic& k, const SpOptions& opt, double cos_t[8],
                             double sin_t[8], bool* phi_constant, bool* quartic_fallback) {
  *quartic_fallback = false;
  const ExtremaCondition x = CalcExtremaCondition(k);
  const double size =
      std::abs(k.a) + std::abs(k.b) + std::abs(k.c) + std::abs(k.d) + std::abs(k.e) + std::abs(k.f);
  const double amp = std::max({x.beta, std::abs(x.gamma), std::abs(x.delta)});
  *phi_constant = !(amp > kPhiConstantRel * size);
  if (*phi_constant) return 0;
  // Normalised so that the quartic's coefficients are O(1).
  const double b = x.beta / amp, g = x.gamma / amp, d = x.delta / amp;
  // (4.24)–(4.26) with R̂ = 1: v = −γu/(βu + δ) on u² + v² = 1 gives
  // β²u⁴ + 2βδu³ + (γ² + δ² − β²)u² − 2βδu − δ² = 0.
  const double quartic[5] = {-d * d, -2 * b * d, g * g + d * d - b * b, 2 * b * d, b * b};
  PolyRootOptions ro;
  ro.tol = opt.quartic_tol;
  ro.max_iters = opt.quartic_max_iters;
  // p(±1) = γ² ≥ 0: extend the interval a little so that roots at u = ±1 show a sign change.
  double roots[4];
  const double lo = -1 - 1e-9, hi = 1 + 1e-9;
  const int nr = opt.quartic_method == SpQuarticMethod::kClosedForm
                     ? SolveQuarticInInterval(quartic, lo, hi, opt.closed_form_polish, ro, roots,
                                              quartic_fallback)
                     : FindPolyRootsInInterval(quartic, lo, hi, ro, roots);
  int n = 0;
  for (int i = 0; i < nr; ++i) {
    const double u = std::clamp(roots[i], -1.0, 1.0);
    const double v0 = std::sqrt(std::max(0.0, 1 - u * u));
    // (4.25) picks the sign of v; evaluate (4.23) for both signs instead of dividing by
    // βu + δ, which vanishes when β = δ = 0 or at the pole of (4.25).
    const double res_pos = std::abs(b * u * v0 + g * u + d * v0);
    const double res_neg = std::abs(-b * u * v0 + g * u - d * v0);
    const bool keep_pos = res_pos <= res_neg || res_pos <= kKeepBothResidual;
    const bool keep_neg = res_neg < res_pos || res_neg <= kKeepBothResidual;
    for (int sgn = 0; sgn < 2; ++sgn) {
      if (!(sgn == 0 ? keep_pos : keep_neg)) continue;
      const double v = sgn == 0 ? v0 : -v0;
      // (4.19): back to the circle's (x, y) = (cos θ, sin θ).
      cos_t[n] = u * x.cos_psi - v * x.sin_psi;
      sin_t[n] = u * x.sin_psi + v * x.cos_psi;
      ++n;
    }
  }
  return n;
}

namespace sp {

void RunSpPassOnConic(const NeedleInV& nv, const LiftedConic& k, const Interval* iv, int n_iv,
                      const SpOptions& opt, bool all, double phi_below, SpPass* out) {
  SpPass& r = *out;
  r.ok = false;
  r.n = 0;
  r.lifted_radius = k.radius;
  r.lift_ok = k.ok;
  if (!r.lift_ok) return;
  const ScaledLiftedCircle& lc = k.lc;
  const CircleConic& conic = k.conic;
  r.phi_size = k.phi_size;
  // (4.17)–(4.26): the extrema of φ on the lifted circle.
  double ct[8], st[8];
  const int n_ext =
      FindConicExtremaOnCircle(conic, opt, ct, st, &r.phi_constant, &r.quartic_fallback);
  if (r.phi_constant) return;
  r.ok = true;
  const double g = conic.c - conic.a;
  const double d2_scale = std::abs(conic.b) + std::abs(g) + std::abs(conic.d) + std::abs(conic.e);
  for (int j = 0; j < n_ext; ++j) {
    const double c = ct[j], sn = st[j];
    // φ''(θ) = −4B xy + 2g(x² − y²) − D x − E y: minima of φ (and flat points) are the
    // candidates for the deepest point; maxima only matter to the sign-change count.
    const double d2phi =
        -4 * conic.b * c * sn + 2 * g * (c * c - sn * sn) - conic.d * c - conic.e * sn;
    const bool is_min = d2phi >= -1e-9 * d2_scale;
    if (!is_min && !all) continue;
    const double phi = conic.Eval(c, sn);
    if (!(phi < phi_below * r.phi_size)) continue;
    // Back to R³ through (4.13) and P (4.2), then to the needle parameter s.
    const Eigen::Vector4d X = lc.center + (c * lc.ax + sn * lc.ay);
    const Eigen::Vector3d rel = ProjectFromS3(X) / k.lambda - nv.o;
    const double rx = rel.dot(nv.e1), ry = rel.dot(nv.e2);
    const double s = WrapTo2Pi(std::atan2(ry, rx));
    const int i = FindInterval(iv, n_iv, s);
    if (i < 0) continue;
    const double s_in = std::clamp(s, iv[i].lo, iv[i].hi);
    const double inv = 1 / std::sqrt(rx * rx + ry * ry);
    const int m = r.n++;
    r.s[m] = s_in;
    if (s_in == s && std::isfinite(inv)) {
      r.cos_s[m] = rx * inv;
      r.sin_s[m] = ry * inv;
    } else {
      r.cos_s[m] = std::cos(s_in);
      r.sin_s[m] = std::sin(s_in);
    }
    r.phi[m] = phi;
    r.is_min[m] = is_min;
    r.interval[m] = i;
  }
}

void RunSpPass(const NeedleInV& nv, double core_r, double tube_t, const Interval* iv, int n_iv,
               const SpOptions& opt, bool all, double phi_below, SpPass* out) {
  LiftedConic k;
  LiftLevelTorus(nv, tube_t, (core_r - tube_t) * (core_r + tube_t), &k);
  RunSpPassOnConic(nv, k, iv, n_iv, opt, all, phi_below, out);
}

void CountSignChanges(const NeedleInV& nv, double core_r, double tube_r, const Interval* iv,
                      int n_iv, const SpPass& pass, SpDiagnostics* diag) {
  const TorusLiftScale scale = CalcTorusLiftScale(core_r, tube_r);
  double min_phi = std::numeric_limits<double>::infinity();
  int changes = 0;
  for (int i = 0; i < n_iv; ++i) {
    double s_list[10], phi_list[10];
    int m = 0;
    for (const double s : {iv[i].lo, iv[i].hi}) {
      s_list[m] = s;
      phi_list[m] = EvalLiftedTorus(scale.alpha, LiftToS3(scale.lambda * nv.PointAt(s)));
      ++m;
    }
    for (int j = 0; j < pass.n && m < 10; ++j) {
      if (pass.interval[j] != i) continue;
      s_list[m] = pass.s[j];
      phi_list[m] = pass.phi[j];
      ++m;
    }
    for (int a = 1; a < m; ++a) {  // insertion sort by s
      for (int b = a; b > 0 && s_list[b] < s_list[b - 1]; --b) {
        std::swap(s_list[b], s_list[b - 1]);
        std::swap(phi_list[b], phi_list[b - 1]);
      }
    }
    for (int a = 0; a < m; ++a) {
      min_phi = std::min(min_phi, phi_list[a]);
      if (a > 0 && (phi_list[a] > 0) != (phi_list[a - 1] > 0)) ++changes;
    }
  }
  diag->min_phi = min_phi;
  diag->num_sign_changes = changes;
}

}  // namespace sp
}  // namespace microdex::geometry
