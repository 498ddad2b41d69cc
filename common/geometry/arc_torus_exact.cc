#include "common/geometry/arc_torus_exact.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/geometry/arc_azimuth_clip.h"

namespace microdex::geometry {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kPi = std::numbers::pi;

// Degree of P (trigonometric) and of its half-angle polynomial Q.
constexpr int kDeg = 4;
constexpr int kN = 2 * kDeg;  // Bernstein degree
// Rounding allowance of a computed Bernstein coefficient, in units of eps times the same
// computation carried out on absolute values (a running error bound with a safety margin).
constexpr double kNoiseFactor = 512;
// A clipped interval is cut into pieces no wider than this before the half-angle map, so
// that |t| ≤ tan(π/8) and the Bernstein form is well conditioned.
constexpr double kMaxPieceWidth_rad = kPi / 2;
// Nodes shorter than this (needle arc length, in units of R) are not subdivided further:
// whatever P does inside is settled through the sign of Φ at the node's ends. In arc length
// rather than in s, because the distance varies on the scale of R whatever the needle radius.
constexpr double kMinNodeLength = 1e-7;
constexpr int kMaxNodesPerQuery = 600;
constexpr int kStackSize = 96;
// Polynomial forms of P kept per query: the clipped pieces and the local re-expansions.
constexpr int kMaxForms = 40;
// After a local re-expansion of a node has been tried, the next try waits until the nodes are
// this many times narrower (a re-expansion at the same scale gives the same conditioning).
constexpr double kReformShrink = 8;
// Split nodes slightly off their middle, so that roots at symmetric positions (common in
// exact test poses) do not fall exactly on a node boundary.
constexpr double kSplit = 0.5 - 1.0 / 128;

// ---- Trigonometric polynomials a[0] + Σ_k a[k] cos ks + b[k] sin ks ---------------------

template <int N>
struct Trig {
  double a[N + 1] = {};
  double b[N + 1] = {};  // b[0] unused
};

// Product, with the product-to-sum identities; `abs_mode` multiplies magnitudes instead and
// gives the running rounding bound of the same computation.
template <int N, int M>
Trig<N + M> Mul(const Trig<N>& p, const Trig<M>& q, bool abs_mode) {
  Trig<N + M> r;
  for (int j = 0; j <= N; ++j) {
    for (int k = 0; k <= M; ++k) {
      const double aa = 0.5 * p.a[j] * q.a[k];
      const double bb = 0.5 * p.b[j] * q.b[k];
      const double ab = 0.5 * p.a[j] * q.b[k];  // cos j · sin k
      const double ba = 0.5 * p.b[j] * q.a[k];  // sin j · cos k
      const int lo = j > k ? j - k : k - j;
      if (abs_mode) {
        r.a[lo] += aa + bb;
        r.a[j + k] += aa + bb;
        r.b[j + k] += ab + ba;
        if (lo != 0) r.b[lo] += ab + ba;
        continue;
      }
      r.a[lo] += aa + bb;
      r.a[j + k] += aa - bb;
      r.b[j + k] += ab + ba;
      if (j > k) {
        r.b[lo] += ba - ab;
      } else if (k > j) {
        r.b[lo] += ab - ba;
      }
    }
  }
  return r;
}

template <int N>
Trig<N> Add(const Trig<N>& p, const Trig<N>& q) {
  Trig<N> r;
  for (int k = 0; k <= N; ++k) {
    r.a[k] = p.a[k] + q.a[k];
    r.b[k] = p.b[k] + q.b[k];
  }
  return r;
}

// Value of a degree ≤ 2 trigonometric polynomial from cos s, sin s, cos 2s, sin 2s.
template <int N>
double Eval2(const Trig<N>& p, double c1, double s1, double c2, double s2) {
  static_assert(N <= 2);
  double v = p.a[0] + p.a[1] * c1 + p.b[1] * s1;
  if constexpr (N == 2) v += p.a[2] * c2 + p.b[2] * s2;
  return v;
}

// ---- Constant tables ---------------------------------------------------------------------

// E_k(t) = (1 + it)^(4+k) (1 − it)^(4−k), k = 0..4: with t = tan(σ/2),
// (1 + t²)⁴ e^{ikσ} = E_k(t), so Q(t) = (1 + t²)⁴ P(m + σ) = Σ_k Re(C_k e^{ikm} E_k(t)).
struct HalfAngleTable {
  double re[kDeg + 1][kN + 1] = {};
  double im[kDeg + 1][kN + 1] = {};
};

constexpr HalfAngleTable MakeHalfAngleTable() {
  HalfAngleTable table;
  for (int k = 0; k <= kDeg; ++k) {
    double re[kN + 1] = {1}, im[kN + 1] = {0};
    for (int f = 0; f < kN; ++f) {
      const double sign = f < kDeg + k ? 1 : -1;  // multiply by (1 + i·sign·t)
      for (int j = f + 1; j >= 1; --j) {
        const double new_re = re[j] - sign * im[j - 1];
        const double new_im = im[j] + sign * re[j - 1];
        re[j] = new_re;
        im[j] = new_im;
      }
    }
    for (int j = 0; j <= kN; ++j) {
      table.re[k][j] = re[j];
      table.im[k][j] = im[j];
    }
  }
  return table;
}

constexpr double Binomial(int n, int k) {
  double r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

// Power basis in x ∈ [−1, 1] to the Bernstein basis in y = (x + 1)/2 ∈ [0, 1].
struct BernsteinTable {
  double m[kN + 1][kN + 1] = {};
  double abs_m[kN + 1][kN + 1] = {};
};

constexpr BernsteinTable MakeBernsteinTable() {
  BernsteinTable table;
  for (int i = 0; i <= kN; ++i) {
    for (int j = 0; j <= kN; ++j) {
      double sum = 0, abs_sum = 0;
      for (int l = 0; l <= std::min(i, j); ++l) {
        double term = Binomial(i, l) / Binomial(kN, l) * Binomial(j, l);
        for (int p = 0; p < l; ++p) term *= 2;
        abs_sum += term;
        sum += ((j - l) % 2 == 0) ? term : -term;
      }
      table.m[i][j] = sum;
      table.abs_m[i][j] = abs_sum;
    }
  }
  return table;
}

constexpr HalfAngleTable kHalfAngle = MakeHalfAngleTable();
constexpr BernsteinTable kBernstein = MakeBernsteinTable();

// ---- The per-query problem ---------------------------------------------------------------

// Quantities along the needle, normalised units (R = 1).
struct Curve {
  ArcInTorusFrame f;
  Trig<2> e, b, zz;  // e = |p_xy|² − 1, B = p_xy·p'_xy, zz' = z z'
  Trig<kDeg> p;      // P = e A² + zz'(A + B)
  Trig<kDeg> p_abs;  // its running rounding bound (without the factor eps)
  // Rounding scales (without the factor eps) of the two ways of getting k − 1 at a point:
  // e/(k + 1) from the coefficients of e (accurate near the degenerate families, where they
  // are small), or k − 1 from the point itself (accurate when the needle is large or far,
  // where the coefficients of e are O(ρ² + |c|²) and cancel down to O(1) near the tube).
  double e_scale = 0;
  double point_scale = 0;
};

struct PointEval {
  double k = 0;    // |p_xy|
  double z = 0;    // p_z
  double d = 0;    // distance to the core circle
  double phi = 0;  // Φ = (k − 1)B + k zz' = k F'/2: the sign of the slope of F
};

PointEval EvalPoint(const Curve& cv, double c1, double s1) {
  const ArcInTorusFrame& f = cv.f;
  const double c2 = c1 * c1 - s1 * s1, s2 = 2 * c1 * s1;
  PointEval pe;
  const double px = f.center.x() + f.radius * (f.u.x() * c1 + f.v.x() * s1);
  const double py = f.center.y() + f.radius * (f.u.y() * c1 + f.v.y() * s1);
  pe.z = f.center.z() + f.radius * (f.u.z() * c1 + f.v.z() * s1);
  pe.k = std::sqrt(px * px + py * py);
  // k − 1 whichever way rounds less here (see Curve).
  const double k_minus_one = cv.e_scale <= cv.point_scale * (pe.k + 1)
                                 ? Eval2(cv.e, c1, s1, c2, s2) / (pe.k + 1)
                                 : pe.k - 1;
  pe.d = std::sqrt(k_minus_one * k_minus_one + pe.z * pe.z);
  pe.phi = k_minus_one * Eval2(cv.b, c1, s1, c2, s2) + pe.k * Eval2(cv.zz, c1, s1, c2, s2);
  return pe;
}

Curve MakeCurve(const ArcInTorusFrame& f) {
  Curve cv;
  cv.f = f;
  const Eigen::Vector3d& c = f.center;
  const Eigen::Vector3d& u = f.u;
  const Eigen::Vector3d& v = f.v;
  const double rho = f.radius, rho2 = rho * rho;
  const double uz = u.z(), vz = v.z(), cz = c.z();
  const double cu_xy = c.x() * u.x() + c.y() * u.y();
  const double cv_xy = c.x() * v.x() + c.y() * v.y();
  const double cu_xy_abs = std::abs(c.x() * u.x()) + std::abs(c.y() * u.y());
  const double cv_xy_abs = std::abs(c.x() * v.x()) + std::abs(c.y() * v.y());
  const double cxy2 = c.x() * c.x() + c.y() * c.y();
  // The coefficients use |u| = |v| = 1 and u·v = 0 (u_xy·v_xy = −u_z v_z, |u_xy|² = 1 − u_z²),
  // so that each is a product of small quantities in the degenerate families: this is what
  // keeps P accurate relative to its own size there.
  Trig<1> a, a_abs;  // A = p·p' = ρ (c·v cos s − c·u sin s)
  a.a[1] = rho * (cv_xy + cz * vz);
  a.b[1] = -rho * (cu_xy + cz * uz);
  a_abs.a[1] = rho * (cv_xy_abs + std::abs(cz * vz));
  a_abs.b[1] = rho * (cu_xy_abs + std::abs(cz * uz));
  Trig<2> b, b_abs;
  b.a[1] = rho * cv_xy;
  b.b[1] = -rho * cu_xy;
  b.a[2] = -rho2 * uz * vz;
  b.b[2] = 0.5 * rho2 * (uz - vz) * (uz + vz);
  b_abs.a[1] = rho * cv_xy_abs;
  b_abs.b[1] = rho * cu_xy_abs;
  b_abs.a[2] = rho2 * std::abs(uz * vz);
  b_abs.b[2] = 0.5 * rho2 * (uz * uz + vz * vz);
  Trig<2> zz, zz_abs;
  zz.a[1] = rho * cz * vz;
  zz.b[1] = -rho * cz * uz;
  zz.a[2] = -b.a[2];
  zz.b[2] = -b.b[2];
  zz_abs.a[1] = rho * std::abs(cz * vz);
  zz_abs.b[1] = rho * std::abs(cz * uz);
  zz_abs.a[2] = b_abs.a[2];
  zz_abs.b[2] = b_abs.b[2];
  Trig<2> e, e_abs;
  e.a[0] = cxy2 + f.radius_minus_one * (rho + 1) - 0.5 * rho2 * (uz * uz + vz * vz);
  e.a[1] = 2 * rho * cu_xy;
  e.b[1] = 2 * rho * cv_xy;
  e.a[2] = -b.b[2];
  e.b[2] = b.a[2];
  e_abs.a[0] = cxy2 + std::abs(f.radius_minus_one) * (rho + 1) + b_abs.b[2];
  e_abs.a[1] = 2 * rho * cu_xy_abs;
  e_abs.b[1] = 2 * rho * cv_xy_abs;
  e_abs.a[2] = b_abs.b[2];
  e_abs.b[2] = b_abs.a[2];
  Trig<2> a_plus_b, a_plus_b_abs;
  a_plus_b.a[1] = rho * (2 * cv_xy + cz * vz);
  a_plus_b.b[1] = -rho * (2 * cu_xy + cz * uz);
  a_plus_b.a[2] = b.a[2];
  a_plus_b.b[2] = b.b[2];
  a_plus_b_abs.a[1] = rho * (2 * cv_xy_abs + std::abs(cz * vz));
  a_plus_b_abs.b[1] = rho * (2 * cu_xy_abs + std::abs(cz * uz));
  a_plus_b_abs.a[2] = b_abs.a[2];
  a_plus_b_abs.b[2] = b_abs.b[2];
  cv.e = e;
  cv.b = b;
  cv.zz = zz;
  cv.p = Add(Mul(e, Mul(a, a, false), false), Mul(zz, a_plus_b, false));
  cv.p_abs = Add(Mul(e_abs, Mul(a_abs, a_abs, true), true), Mul(zz_abs, a_plus_b_abs, true));
  cv.e_scale = e_abs.a[0] + e_abs.a[1] + e_abs.b[1] + e_abs.a[2] + e_abs.b[2];
  cv.point_scale = 1 + std::abs(c.x()) + std::abs(c.y()) + 2 * rho;
  return cv;
}

// ---- Power-basis polynomials in t, for the local forms ----------------------------------

// Coefficients with a first-order bound of their error, in units of eps: the local form
// starts from the point q = p(m), which carries the rounding of a sum of terms much larger
// than itself when the needle is large or far; a bound on magnitudes alone would take that
// rounding as relative to |q| squared instead of |q| times its error.
template <int N>
struct PolyE {
  double v[N + 1] = {};
  double e[N + 1] = {};
};

template <int N, int M>
PolyE<N + M> PolyMul(const PolyE<N>& p, const PolyE<M>& q) {
  PolyE<N + M> r;
  for (int j = 0; j <= N; ++j) {
    for (int k = 0; k <= M; ++k) {
      const double pq = p.v[j] * q.v[k];
      r.v[j + k] += pq;
      r.e[j + k] += std::abs(p.v[j]) * q.e[k] + p.e[j] * std::abs(q.v[k]) + std::abs(pq);
    }
  }
  return r;
}

template <int N>
PolyE<N> PolyAdd(const PolyE<N>& p, const PolyE<N>& q) {
  PolyE<N> r;
  for (int j = 0; j <= N; ++j) {
    r.v[j] = p.v[j] + q.v[j];
    r.e[j] = p.e[j] + q.e[j] + std::abs(p.v[j]) + std::abs(q.v[j]);
  }
  return r;
}

// One polynomial form of P over [begin, end] = [m − w, m + w], w ≤ π/4, in the variable
// x = tan((s − m)/2) / τ ∈ [−1, 1], τ = tan(w/2): Q(x) = Σ q[j] x^j ∝ P. Either the global
// trigonometric coefficients re-centred at m (the clipped pieces), or a local expansion about
// the needle point at m (MakeLocalForm).
// No member initialisers: a query keeps kMaxForms of them and fills only those it uses.
struct Piece {
  double begin, end;  // needle parameter range
  double m, cos_m, sin_m, tau;
  double q[kN + 1];
};

struct Node {
  double b[kN + 1];
  double noise;   // rounding bound of every b[i]
  double y0, y1;  // in the form's y = (x + 1)/2
  int form;       // index of its Piece
  // A local re-expansion is tried only on nodes no wider (in s) than this.
  double reform_below_rad;
};

// The deepest needle point so far, at s = m + 2 atan(t) (the arctangent is taken once, at
// the end).
struct Best {
  double d = -1;
  double cos_s = 1, sin_s = 0;
  double m = 0, t = 0;
  double lo = 0, hi = 0;  // the piece: s is clamped to it against rounding at its ends
  double s() const { return std::clamp(m + 2 * std::atan(t), lo, hi); }
};

// Bernstein coefficients on [−1, 1] of the form's power coefficients, and their rounding
// bound from the bound q_abs of the power coefficients.
void ToBernstein(const Piece& pc, const double* q_abs, Node* root) {
  root->y0 = 0;
  root->y1 = 1;
  root->noise = 0;
  for (int i = 0; i <= kN; ++i) {
    double sum = 0, abs_sum = 0;
    for (int j = 0; j <= kN; ++j) {
      sum += kBernstein.m[i][j] * pc.q[j];
      abs_sum += kBernstein.abs_m[i][j] * q_abs[j];
    }
    root->b[i] = sum;
    root->noise = std::max(root->noise, kNoiseFactor * kEps * abs_sum);
  }
}

void SetPieceFrame(double sa, double sb, Piece* pc) {
  pc->begin = sa;
  pc->end = sb;
  pc->m = 0.5 * (sa + sb);
  pc->tau = std::tan(0.25 * (sb - sa));
  pc->cos_m = std::cos(pc->m);
  pc->sin_m = std::sin(pc->m);
}

// The global form: P's trigonometric coefficients (accurate relative to P's own size near the
// degenerate families) turned into Q on the piece.
void MakeGlobalForm(const Curve& cv, double sa, double sb, Piece* pc, Node* root) {
  SetPieceFrame(sa, sb, pc);
  // D_k = C_k e^{ikm}, C_k = a_k − i b_k, so that Re(D_k e^{ikσ}) is the k-th term of P.
  double d_re[kDeg + 1], d_im[kDeg + 1], c_abs[kDeg + 1];
  double ck = 1, sk = 0;
  for (int k = 0; k <= kDeg; ++k) {
    d_re[k] = cv.p.a[k] * ck + cv.p.b[k] * sk;
    d_im[k] = cv.p.a[k] * sk - cv.p.b[k] * ck;
    c_abs[k] = cv.p_abs.a[k] + cv.p_abs.b[k];
    const double next_c = ck * pc->cos_m - sk * pc->sin_m;
    sk = sk * pc->cos_m + ck * pc->sin_m;
    ck = next_c;
  }
  double q_abs[kN + 1];
  double tau_j = 1;
  for (int j = 0; j <= kN; ++j) {
    double sum = 0, abs_sum = 0;
    for (int k = 0; k <= kDeg; ++k) {
      sum += d_re[k] * kHalfAngle.re[k][j] - d_im[k] * kHalfAngle.im[k][j];
      abs_sum += c_abs[k] * (std::abs(kHalfAngle.re[k][j]) + std::abs(kHalfAngle.im[k][j]));
    }
    pc->q[j] = sum * tau_j;
    q_abs[j] = abs_sum * tau_j;
    tau_j *= pc->tau;
  }
  ToBernstein(*pc, q_abs, root);
}

// The local form: the needle written about its point q = p(m) with the frame turned to m,
// p(m + σ) = q + ρ(u_m (cos σ − 1) + v_m sin σ), so that with t = tan(σ/2)
//   W = (1 + t²) p  = q + 2ρ v_m t + (q − 2ρ u_m) t²,
//   V = (1 + t²) p' = ρ v_m − 2ρ u_m t − ρ v_m t²,
//   a = (1 + t²) A  = ρ c·v_m − 2ρ c·u_m t − ρ c·v_m t²   (A = p·p' = c·p'),
// and (1 + t²)⁴ P = E a² + Z (a (1 + t²) + b) with E = |W_xy|² − (1 + t²)², Z = W_z V_z,
// b = W_xy·V_xy (the same identity as the global form). Every coefficient is of the size of
// the quantities near q, whereas the global coefficients are of the size of (|c| + ρ)⁶ and
// cancel down to P near the tube when the needle is large or far (ρ or |c| ≫ R): there only
// an arc of length O(R), a parameter interval O(R/ρ), is near the tube, and the local form
// over it keeps the relative accuracy the global one loses.
void MakeLocalForm(const Curve& cv, double sa, double sb, Piece* pc, Node* root) {
  SetPieceFrame(sa, sb, pc);
  const ArcInTorusFrame& f = cv.f;
  const double rho = f.radius;
  const Eigen::Vector3d um = f.u * pc->cos_m + f.v * pc->sin_m;
  const Eigen::Vector3d vm = f.v * pc->cos_m - f.u * pc->sin_m;
  const Eigen::Vector3d q = f.center + rho * um;
  // The error of q: the rounding of its sum, relative to the magnitudes of the terms.
  const Eigen::Vector3d q_err = 2 * (f.center.cwiseAbs() + rho * um.cwiseAbs());
  PolyE<2> w[3], v[3];
  for (int i = 0; i < 3; ++i) {
    w[i].v[0] = q[i];
    w[i].e[0] = q_err[i];
    w[i].v[1] = 2 * rho * vm[i];
    w[i].e[1] = 2 * std::abs(w[i].v[1]);
    w[i].v[2] = q[i] - 2 * rho * um[i];
    w[i].e[2] = q_err[i] + std::abs(q[i]) + 4 * rho * std::abs(um[i]);
    v[i].v[0] = rho * vm[i];
    v[i].v[1] = -2 * rho * um[i];
    v[i].v[2] = -rho * vm[i];
    for (int j = 0; j < 3; ++j) v[i].e[j] = 2 * std::abs(v[i].v[j]);
  }
  // A = p·p' = c·p' (|u| = |v| = 1, u ⊥ v), from c rather than q: no error of q enters.
  const double cvm_abs = f.center.cwiseAbs().dot(vm.cwiseAbs());
  const double cum_abs = f.center.cwiseAbs().dot(um.cwiseAbs());
  PolyE<2> a;
  a.v[0] = rho * f.center.dot(vm);
  a.v[1] = -2 * rho * f.center.dot(um);
  a.v[2] = -a.v[0];
  a.e[0] = a.e[2] = 4 * rho * cvm_abs;
  a.e[1] = 8 * rho * cum_abs;
  PolyE<4> e = PolyAdd(PolyMul(w[0], w[0]), PolyMul(w[1], w[1]));
  constexpr double kOnePlusT2Squared[5] = {1, 0, 2, 0, 1};
  for (int j = 0; j <= 4; ++j) {
    e.e[j] += std::abs(e.v[j]) + kOnePlusT2Squared[j];
    e.v[j] -= kOnePlusT2Squared[j];
  }
  const PolyE<4> b = PolyAdd(PolyMul(w[0], v[0]), PolyMul(w[1], v[1]));
  const PolyE<4> z = PolyMul(w[2], v[2]);
  // a (1 + t²) + b.
  PolyE<4> apb = b;
  for (int j = 0; j <= 2; ++j) {
    for (int k : {j, j + 2}) {
      apb.e[k] += a.e[j] + std::abs(apb.v[k]) + std::abs(a.v[j]);
      apb.v[k] += a.v[j];
    }
  }
  const PolyE<kN> p = PolyAdd(PolyMul(e, PolyMul(a, a)), PolyMul(z, apb));
  double q_bound[kN + 1];
  double tau_j = 1;
  for (int j = 0; j <= kN; ++j) {
    pc->q[j] = p.v[j] * tau_j;
    q_bound[j] = p.e[j] * tau_j;
    tau_j *= pc->tau;
  }
  ToBernstein(*pc, q_bound, root);
}

// Rounding of a node relative to its largest coefficient (∞ when they all vanish).
double RelativeNoise(const Node& node) {
  double max_b = 0;
  for (double b : node.b) max_b = std::max(max_b, std::abs(b));
  return max_b > 0 ? node.noise / max_b : std::numeric_limits<double>::infinity();
}

class Solver {
 public:
  explicit Solver(const Curve& cv)
      : cv_(cv), min_node_width_rad_(kMinNodeLength / std::max(1.0, cv.f.radius)) {}

  void SolveInterval(double s_begin, double s_end) {
    const double width = s_end - s_begin;
    const int pieces = std::max(1, static_cast<int>(std::ceil(width / kMaxPieceWidth_rad)));
    for (int i = 0; i < pieces; ++i) {
      const double a = s_begin + width * i / pieces;
      const double b = i + 1 == pieces ? s_end : s_begin + width * (i + 1) / pieces;
      SolvePiece(a, b);
    }
  }

  const Best& best() const { return best_; }
  ExactDiagnostics& diagnostics() { return diag_; }

 private:
  // The needle point at the form variable x, through the half-angle formulas (no
  // trigonometric call); it becomes the best one if it is deeper.
  PointEval EvalX(const Piece& pc, double x) {
    const double t = pc.tau * x;
    const double den = 1 + t * t;
    const double cs = (1 - t * t) / den, sn = 2 * t / den;
    const double c1 = pc.cos_m * cs - pc.sin_m * sn;
    const double s1 = pc.sin_m * cs + pc.cos_m * sn;
    const PointEval pe = EvalPoint(cv_, c1, s1);
    if (pe.d > best_.d) best_ = {pe.d, c1, s1, pc.m, t, pc.begin, pc.end};
    return pe;
  }

  // Needle parameter at the form variable y = (x + 1)/2.
  static double SAtY(const Piece& pc, double y) {
    if (y <= 0) return pc.begin;
    if (y >= 1) return pc.end;
    return std::clamp(pc.m + 2 * std::atan(pc.tau * (2 * y - 1)), pc.begin, pc.end);
  }

  void SolvePiece(double sa, double sb) {
    if (num_forms_ >= kMaxForms) return;  // never with ≤ 3 intervals of ≤ 5 pieces
    Node root;
    root.form = num_forms_++;
    MakeGlobalForm(cv_, sa, sb, &forms_[root.form], &root);
    root.reform_below_rad = std::numeric_limits<double>::infinity();
    // The piece's ends are candidates (the clipped interval's ends among them).
    EvalX(forms_[root.form], -1);
    EvalX(forms_[root.form], 1);
    Isolate(root);
  }

  // Replaces a node that rounding leaves undecided by the local form over the same needle
  // parameters, when that form is better conditioned.
  void TryLocalForm(Node* node) {
    const Piece& pc = forms_[node->form];
    const double sa = SAtY(pc, node->y0), sb = SAtY(pc, node->y1);
    node->reform_below_rad = (sb - sa) / kReformShrink;
    if (num_forms_ >= kMaxForms || !(sb > sa)) return;
    Node local;
    MakeLocalForm(cv_, sa, sb, &forms_[num_forms_], &local);
    if (!(RelativeNoise(local) < RelativeNoise(*node))) return;
    ++diag_.num_local_forms;
    local.form = num_forms_++;
    local.reform_below_rad = node->reform_below_rad;
    *node = local;
  }

  void Isolate(const Node& root) {
    Node stack[kStackSize];
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
      Node node = stack[--top];
      ++diag_.num_nodes;
      int signs[kN + 1];
      bool any_fuzzy = false, all_fuzzy = true;
      int variations = 0;
      for (int attempt = 0; attempt < 2; ++attempt) {
        any_fuzzy = false;
        all_fuzzy = true;
        for (int i = 0; i <= kN; ++i) {
          if (std::abs(node.b[i]) <= node.noise) {
            signs[i] = 0;
            any_fuzzy = true;
          } else {
            signs[i] = node.b[i] > 0 ? 1 : -1;
            all_fuzzy = false;
          }
        }
        variations = 0;
        int last = 0;
        for (int i = 0; i <= kN; ++i) {
          if (signs[i] == 0) continue;
          if (last != 0 && signs[i] != last) ++variations;
          last = signs[i];
        }
        // Rounding leaves the node undecided: a local form may resolve it (once per scale).
        const Piece& pc = forms_[node.form];
        const double width_rad = (node.y1 - node.y0) * (pc.end - pc.begin);
        if (attempt > 0 || !any_fuzzy || width_rad > node.reform_below_rad) break;
        const int form_before = node.form;
        TryLocalForm(&node);
        if (node.form == form_before) break;
      }
      if (!any_fuzzy && variations == 0) continue;
      const Piece& pc = forms_[node.form];
      if (!any_fuzzy && variations == 1) {
        SolveSimpleRoot(pc, node);
        continue;
      }
      const bool too_small = (node.y1 - node.y0) * (pc.end - pc.begin) < min_node_width_rad_;
      if (all_fuzzy || too_small || top + 2 > kStackSize || diag_.num_nodes >= kMaxNodesPerQuery) {
        if (diag_.num_nodes >= kMaxNodesPerQuery) diag_.node_budget_hit = true;
        SettleByPhi(pc, node);
        continue;
      }
      // De Casteljau split at kSplit; the rounding of the convex combinations is added to
      // the children's noise.
      Node left, right;
      double b[kN + 1];
      std::copy(node.b, node.b + kN + 1, b);
      double max_b = 0;
      for (int i = 0; i <= kN; ++i) max_b = std::max(max_b, std::abs(b[i]));
      for (int level = 0; level <= kN; ++level) {
        left.b[level] = b[0];
        right.b[kN - level] = b[kN - level];
        for (int i = 0; i < kN - level; ++i) b[i] = (1 - kSplit) * b[i] + kSplit * b[i + 1];
      }
      left.noise = right.noise = node.noise + 2 * kN * kEps * max_b;
      const double ym = node.y0 + kSplit * (node.y1 - node.y0);
      left.y0 = node.y0;
      left.y1 = ym;
      right.y0 = ym;
      right.y1 = node.y1;
      left.form = right.form = node.form;
      left.reform_below_rad = right.reform_below_rad = node.reform_below_rad;
      stack[top++] = right;
      stack[top++] = left;
    }
  }

  static double EvalQ(const Piece& pc, double x, double* dq) {
    double q = pc.q[kN], d = 0;
    for (int j = kN - 1; j >= 0; --j) {
      d = d * x + q;
      q = q * x + pc.q[j];
    }
    *dq = d;
    return q;
  }

  // Exactly one simple root of Q inside the node: safeguarded Newton on Q.
  void SolveSimpleRoot(const Piece& pc, const Node& node) {
    ++diag_.num_roots;
    double lo = 2 * node.y0 - 1, hi = 2 * node.y1 - 1;
    const bool lo_negative = node.b[0] < 0;
    double x = lo + (hi - lo) * node.b[0] / (node.b[0] - node.b[kN]);
    if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
    for (int it = 0; it < 60; ++it) {
      double dq;
      const double q = EvalQ(pc, x, &dq);
      if (q == 0) break;
      if ((q < 0) == lo_negative) {
        lo = x;
      } else {
        hi = x;
      }
      double next = x - q / dq;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      const bool done = std::abs(next - x) <= 4 * kEps * std::max(1.0, std::abs(x));
      x = next;
      if (done || hi - lo <= 4 * kEps) break;
    }
    EvalX(pc, x);
  }

  // P could not be resolved inside the node (it is zero to rounding there, or the node
  // reached the minimal width): take the node's ends, and the maximum of F inside where
  // Φ changes sign from + to −, found by bisection (Φ is well conditioned there, P is not).
  void SettleByPhi(const Piece& pc, const Node& node) {
    ++diag_.num_fuzzy;
    double lo = 2 * node.y0 - 1, hi = 2 * node.y1 - 1;
    const PointEval pe_lo = EvalX(pc, lo);
    const PointEval pe_hi = EvalX(pc, hi);
    if (!(pe_lo.phi > 0 && pe_hi.phi < 0)) return;
    for (int it = 0; it < 80 && hi - lo > 2 * kEps * std::max(1.0, std::abs(lo)); ++it) {
      const double mid = 0.5 * (lo + hi);
      const PointEval pe = EvalX(pc, mid);
      if (pe.phi > 0) {
        lo = mid;
      } else if (pe.phi < 0) {
        hi = mid;
      } else {
        break;
      }
    }
  }

  const Curve& cv_;
  const double min_node_width_rad_;
  Piece forms_[kMaxForms];
  int num_forms_ = 0;
  Best best_;
  ExactDiagnostics diag_;
};

}  // namespace

ArcTorusClearance MakeArcTorusClearance(const TorusSegmentDef& torus, const ArcInTorusFrame& f,
                                        double s_rad, double cos_s, double sin_s,
                                        double distance_to_core_m) {
  const double R = torus.core_radius_m, r = torus.tube_radius_m;
  ArcTorusClearance out;
  out.status = ClearanceStatus::kOk;
  out.clearance_m = r - distance_to_core_m;
  out.contact = out.clearance_m <= 0;
  out.s_rad = s_rad;
  const Eigen::Vector3d p_V = R * (f.center + f.radius * (f.u * cos_s + f.v * sin_s));
  const double k = std::sqrt(p_V.x() * p_V.x() + p_V.y() * p_V.y());
  // Nearest core point; on the z axis every core point is nearest: take azimuth 0.
  const Eigen::Vector3d radial =
      k > 0 ? Eigen::Vector3d(p_V.x() / k, p_V.y() / k, 0) : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d q_V = R * radial;
  const Eigen::Vector3d offset = p_V - q_V;
  const double n = offset.norm();
  // On the core circle every wall point at distance r is nearest: take the outward one.
  const Eigen::Vector3d dir = n > 0 ? Eigen::Vector3d(offset / n) : radial;
  out.p_WD = torus.X_WV * p_V;
  out.p_WB = torus.X_WV * Eigen::Vector3d(q_V + r * dir);
  return out;
}

ArcTorusClearance CalcArcTorusClearanceExact(const ArcDef& arc, const TorusSegmentDef& torus,
                                             ExactDiagnostics* diagnostics) {
  ArcTorusClearance out;
  ArcInTorusFrame frame;
  AzimuthIntervals intervals;
  if (!StartClippedQuery(arc, torus, frame, intervals, out)) {
    if (out.status == ClearanceStatus::kEmptyRange && diagnostics != nullptr) *diagnostics = {};
    return out;
  }
  const Curve curve = MakeCurve(frame);
  Solver solver(curve);
  for (int i = 0; i < intervals.count; ++i) {
    solver.SolveInterval(intervals.begin[i], intervals.end[i]);
  }
  solver.diagnostics().num_intervals = intervals.count;
  if (diagnostics != nullptr) *diagnostics = solver.diagnostics();
  const Best& best = solver.best();
  return MakeArcTorusClearance(torus, frame, best.s(), best.cos_s, best.sin_s,
                               best.d * torus.core_radius_m);
}

ArcTorusClearance CalcArcTorusClearanceExact(const ArcDef& arc, const TorusSegmentDef& torus) {
  return CalcArcTorusClearanceExact(arc, torus, nullptr);
}

}  // namespace microdex::geometry
