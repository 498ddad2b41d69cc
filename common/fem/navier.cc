#include "common/fem/navier.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace microdex::fem {
namespace {

constexpr double kPi = std::numbers::pi;

// Y_k(y, η) = sinh(k y<) sinh(k(B − y>)) / (k sinh kB), written with decaying exponentials.
double GreenY(double k, double y, double eta, double b) {
  const double e = std::exp(-2 * k * b);
  const double num = std::exp(-k * std::abs(y - eta)) - std::exp(-k * (y + eta)) -
                     std::exp(-k * (2 * b - y - eta)) + std::exp(-k * (2 * b - std::abs(y - eta)));
  return num / (2 * k * (1 - e));
}

double ChebyshevT(int l, double s) { return std::cos(l * std::acos(std::clamp(s, -1.0, 1.0))); }

// ∫ cos(lθ) dθ antiderivative.
double CosIntegral(int l, double theta) { return l == 0 ? theta : std::sin(l * theta) / l; }

}  // namespace

double NavierDoubleSeries_m(const NavierDomain& domain, const UniformLineLoad& load, double x_m,
                            double y_m, int m_terms, int n_terms) {
  const double lx = domain.length_x_m, ly = domain.length_y_m;
  const double gt = domain.shear_modulus_Pa * domain.thickness_m;
  double w = 0;
  for (int m = 1; m <= m_terms; ++m) {
    const double cx = std::cos(m * kPi * load.x1_m / lx) - std::cos(m * kPi * load.x2_m / lx);
    const double sx = std::sin(m * kPi * x_m / lx);
    for (int n = 1; n <= n_terms; ++n) {
      const double p_mn =
          4 * load.q_N_per_m / (m * kPi * ly) * std::sin(n * kPi * load.y1_m / ly) * cx;  // (A.6)
      const double km = m * kPi / lx, kn = n * kPi / ly;
      const double w_mn = p_mn / (gt * (km * km + kn * kn));  // (A.10)
      w += w_mn * sx * std::sin(n * kPi * y_m / ly);          // (A.3)
    }
  }
  return w;
}

double NavierPointLoadDisplacement_m_per_N(const NavierDomain& domain, double xi_m, double eta_m,
                                           double x_m, double y_m) {
  if (x_m == xi_m) return std::numeric_limits<double>::quiet_NaN();
  const double gt = domain.shear_modulus_Pa * domain.thickness_m;
  const double lx = domain.length_x_m, ly = domain.length_y_m;
  const double lo = std::min(x_m, xi_m), hi = std::max(x_m, xi_m);
  double sum = 0;
  for (int n = 1; n < 10000000; ++n) {
    const double k = n * std::numbers::pi / ly;
    const double a = k * lo, b = k * (lx - hi), c = k * lx;
    // sinh a sinh b / sinh c without overflow.
    const double decay = std::exp(a + b - c);
    const double ratio =
        decay * (1 - std::exp(-2 * a)) * (1 - std::exp(-2 * b)) / (2 * (1 - std::exp(-2 * c)));
    sum += 2 * std::sin(k * eta_m) * std::sin(k * y_m) * ratio / (gt * ly * k);
    if (decay < 1e-17) break;
  }
  return sum;
}

double NavierLineLoadDisplacement_m(const NavierDomain& domain, const UniformLineLoad& load,
                                    double x_m, double y_m, double rel_tol, int max_terms,
                                    int* terms_used) {
  const double lx = domain.length_x_m, ly = domain.length_y_m;
  const double gt = domain.shear_modulus_Pa * domain.thickness_m;
  const double dy = std::abs(y_m - load.y1_m);
  double w = 0;
  int m = 1;
  for (; m <= max_terms; ++m) {
    const double k = m * kPi / lx;
    const double cx = std::cos(k * load.x1_m) - std::cos(k * load.x2_m);
    // Σ_n W_mn sin(nπy/B) = (2q / (mπ G t)) [cos − cos] Y_k(y, y₁)
    const double term = 2 * load.q_N_per_m / (m * kPi * gt) * cx * std::sin(k * x_m) *
                        GreenY(k, y_m, load.y1_m, ly);
    w += term;
    // Bound of every later term: |term_m'| ≤ (4|q| / (m'π G t)) e^{−k'|Δy|} / (2k'(1 − e^{−2k'B})).
    const double ratio = std::exp(-kPi * dy / lx);
    const double envelope = 4 * std::abs(load.q_N_per_m) / (m * kPi * gt) * std::exp(-k * dy) /
                            (2 * k * (1 - std::exp(-2 * k * ly)));
    const double tail = ratio < 1 ? envelope * ratio / (1 - ratio) : envelope * max_terms;
    if (tail <= rel_tol * std::abs(w) || tail == 0) break;
  }
  if (terms_used != nullptr) *terms_used = std::min(m, max_terms);
  return w;
}

NavierBar::NavierBar(const NavierDomain& domain, double x1_m, double x2_m, double y1_m,
                     double w_bar_m, int num_modes, int max_series_terms)
    : domain_(domain), x1_m_(x1_m), x2_m_(x2_m), y1_m_(y1_m), w_bar_m_(w_bar_m) {
  const double lx = domain.length_x_m, ly = domain.length_y_m;
  if (!(0 < x1_m && x1_m < x2_m && x2_m < lx && 0 < y1_m && y1_m < ly) || num_modes < 1) {
    throw std::invalid_argument("NavierBar: expected 0 < x1 < x2 < Lx, 0 < y1 < Ly, modes ≥ 1");
  }
  xc_m_ = 0.5 * (x1_m + x2_m);
  a_m_ = 0.5 * (x2_m - x1_m);
  // Remainder of the m-sum: terms (2/L) sin sin (Y_k − 1/2k), bounded by
  // (2/L) e^{−2k d} / (k (1 − e^{−2kB})) with d the bar's distance to the nearer y edge.
  const double d = std::min(y1_m, ly - y1_m);
  const double ratio = std::exp(-2 * kPi * d / lx);
  int m_max = 1;
  for (; m_max < 100000; ++m_max) {
    const double k = m_max * kPi / lx;
    const double envelope = (2 / lx) * std::exp(-2 * k * d) / (k * (1 - std::exp(-2 * k * ly)));
    // compared with the smooth kernel's size, which is O(1/2π · |ln(π a / L)|) ≳ 1e-2
    if (envelope * ratio / (1 - ratio) < 1e-12 * 1e-2) break;
  }
  remainder_terms_ = m_max;

  const int q = 2 * num_modes + 16;  // Gauss–Chebyshev points
  std::vector<double> s(q), x(q);
  for (int i = 0; i < q; ++i) {
    s[i] = std::cos((2 * i + 1) * kPi / (2 * q));
    x[i] = xc_m_ + a_m_ * s[i];
  }
  Eigen::MatrixXd kernel(q, q);
  for (int i = 0; i < q; ++i) {
    for (int j = i; j < q; ++j) kernel(i, j) = kernel(j, i) = SmoothKernel(x[i], x[j]);
  }
  Eigen::MatrixXd t(num_modes, q);
  for (int l = 0; l < num_modes; ++l) {
    for (int i = 0; i < q; ++i) t(l, i) = ChebyshevT(l, s[i]);
  }
  const double w = kPi / q;
  Eigen::MatrixXd a = (w * w) * (t * kernel * t.transpose());
  // Exact Chebyshev integrals of the logarithm: ∫ ln|s − t| T_l(t)/√(1−t²) dt = −π ln 2 (l = 0),
  // −(π/l) T_l(s) (l ≥ 1); with −(1/2π)(ln a + ln|s − t|) and the test weight T_k/√(1−s²).
  a(0, 0) += -(kPi / 2) * std::log(a_m_ / 2);
  for (int l = 1; l < num_modes; ++l) a(l, l) += kPi / (4.0 * l);
  a /= domain.shear_modulus_Pa * domain.thickness_m;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(num_modes);
  rhs(0) = kPi * w_bar_m;
  const Eigen::VectorXd c = a.partialPivLu().solve(rhs);
  c_.assign(c.data(), c.data() + num_modes);
  // ∫ e^{iβs} T_l(s)/√(1 − s²) ds = π i^l J_l(β), so the sine moments of the load are Bessel sums.
  load_sine_.resize(max_series_terms);
  for (int m = 1; m <= max_series_terms; ++m) {
    const double k = m * kPi / lx;
    const double alpha = k * xc_m_, beta = k * a_m_;
    double sum = 0;
    for (int l = 0; l < num_modes; ++l) {
      const double j = std::cyl_bessel_j(static_cast<double>(l), beta);
      const double re = (l % 4 == 0) ? 1 : (l % 4 == 2 ? -1 : 0);
      const double im = (l % 4 == 1) ? 1 : (l % 4 == 3 ? -1 : 0);
      sum += c_[l] * kPi * (std::sin(alpha) * re + std::cos(alpha) * im) * j;
    }
    load_sine_[m - 1] = sum;
  }
}

double NavierBar::Displacement_m(double x_m, double y_m) const {
  const double lx = domain_.length_x_m, ly = domain_.length_y_m;
  const double gt = domain_.shear_modulus_Pa * domain_.thickness_m;
  const double dy = std::abs(y_m - y1_m_);
  const double ratio = std::exp(-kPi * dy / lx);
  // |S_m| ≤ π Σ|c_l| since |J_l| ≤ 1: a bound that does not vanish with S_m (S_m = 0 for
  // every even m when the bar is centred, which must not stop the sum).
  double s_max = 0;
  for (double c : c_) s_max += kPi * std::abs(c);
  double w = 0;
  for (size_t mi = 0; mi < load_sine_.size(); ++mi) {
    const double k = (mi + 1) * kPi / lx;
    // (A.3) with the n-sum in closed form: w = Σ_m (2/(L G t)) sin(kx) Y_k(y, y₁) S_m.
    w += 2 / (lx * gt) * std::sin(k * x_m) * GreenY(k, y_m, y1_m_, ly) * load_sine_[mi];
    const double bound =
        2 / (lx * gt) * std::exp(-k * dy) / (2 * k * (1 - std::exp(-2 * k * ly))) * s_max * 2;
    if (ratio < 1 && bound * ratio / (1 - ratio) < 1e-12 * std::abs(w)) break;
  }
  return w;
}

double NavierBar::SmoothKernel(double x_m, double xi_m) const {
  const double lx = domain_.length_x_m, ly = domain_.length_y_m;
  const double d = x_m - xi_m;
  const double ratio_log = std::abs(d) < 1e-14 * lx
                               ? std::log(kPi / (2 * lx))
                               : std::log(std::abs(std::sin(kPi * d / (2 * lx))) / std::abs(d));
  double s = (std::log(std::abs(std::sin(kPi * (x_m + xi_m) / (2 * lx)))) - ratio_log) / (2 * kPi);
  const double y = y1_m_;
  for (int m = 1; m <= remainder_terms_; ++m) {
    const double k = m * kPi / lx;
    const double e = std::exp(-2 * k * ly);
    const double y_minus = (-std::exp(-2 * k * y) - std::exp(-2 * k * (ly - y)) + 2 * e) /
                           (2 * k * (1 - e));  // Y_k(y₁, y₁) − 1/(2k)
    s += (2 / lx) * std::sin(k * x_m) * std::sin(k * xi_m) * y_minus;
  }
  return s;
}

double NavierBar::TotalForce_N() const { return kPi * c_[0]; }

double NavierBar::LoadDensity_N_per_m(double x_m) const {
  const double s = (x_m - xc_m_) / a_m_;
  if (!(std::abs(s) < 1)) return 0.0;
  double sum = 0;
  for (size_t l = 0; l < c_.size(); ++l) sum += c_[l] * ChebyshevT(static_cast<int>(l), s);
  return sum / (a_m_ * std::sqrt(1 - s * s));
}

// ∫_{xa}^{xb} q(x) (α + β s(x)) dx, s = (x − x_c)/a, exactly: with s = cos θ the weight
// disappears and cos(lθ)(α + β cos θ) integrates in closed form.
double NavierBar::LinearIntegral(double xa_m, double xb_m, double alpha, double beta) const {
  // Snap to the bar ends: acos is steep there (an ulp off 1 moves θ by 2e-8).
  auto to_s = [&](double x) {
    const double s = std::clamp((x - xc_m_) / a_m_, -1.0, 1.0);
    return std::abs(std::abs(s) - 1) < 1e-12 ? std::copysign(1.0, s) : s;
  };
  const double sa = to_s(xa_m), sb = to_s(xb_m);
  if (!(sb > sa)) return 0.0;
  const double th_lo = std::acos(sb), th_hi = std::acos(sa);  // θ decreases with s
  double sum = 0;
  for (size_t li = 0; li < c_.size(); ++li) {
    const int l = static_cast<int>(li);
    auto span = [&](int k) { return CosIntegral(k, th_hi) - CosIntegral(k, th_lo); };
    sum += c_[li] * (alpha * span(l) + 0.5 * beta * (span(l + 1) + span(std::abs(l - 1))));
  }
  return sum;
}

double NavierBar::IntervalForce_N(double xa_m, double xb_m) const {
  return LinearIntegral(xa_m, xb_m, 1.0, 0.0);
}

double NavierBar::HatForce_N(double x_node_m, double h_m) const {
  // φ = 1 − |x − x_n|/h; in s: x = x_c + a s.
  const double left =
      LinearIntegral(x_node_m - h_m, x_node_m, 1 + (xc_m_ - x_node_m) / h_m, a_m_ / h_m);
  const double right =
      LinearIntegral(x_node_m, x_node_m + h_m, 1 - (xc_m_ - x_node_m) / h_m, -a_m_ / h_m);
  return left + right;
}

double NavierBar::BarDisplacement_m(double x_m) const {
  const double s0 = std::clamp((x_m - xc_m_) / a_m_, -1.0, 1.0);
  // Logarithmic part exactly, smooth part by Gauss–Chebyshev.
  double w = -(c_[0] * (kPi * std::log(a_m_) - kPi * std::log(2.0))) / (2 * kPi);
  for (size_t l = 1; l < c_.size(); ++l) {
    w += c_[l] * (kPi / l) * ChebyshevT(static_cast<int>(l), s0) / (2 * kPi);
  }
  const int q = 4 * static_cast<int>(c_.size()) + 32;
  for (int j = 0; j < q; ++j) {
    const double t = std::cos((2 * j + 1) * kPi / (2 * q));
    double ql = 0;
    for (size_t l = 0; l < c_.size(); ++l) ql += c_[l] * ChebyshevT(static_cast<int>(l), t);
    w += (kPi / q) * ql * SmoothKernel(x_m, xc_m_ + a_m_ * t);
  }
  return w / (domain_.shear_modulus_Pa * domain_.thickness_m);
}

}  // namespace microdex::fem
