#pragma once
// Navier's double-series solution of the antiplane problem on the Lx × Ly rectangle with
// fixed edges (thesis appendix A), and the reference for the thesis's study: the line-load
// distribution along a bar that holds the bar at a prescribed displacement.
//
// With the slab thickness t the equation is G t ∇²w + p = 0 (p in N/m², line loads in N/m).
// The OCR of (A.7), (A.9)–(A.11) writes L where B is meant; the coefficients used here are
//   P_mn = 4q/(mπB) · sin(nπy₁/B) · [cos(mπx₁/L) − cos(mπx₂/L)]              (A.6)
//   W_mn = P_mn / (G t [(mπ/L)² + (nπ/B)²])                                  (A.10)
// checked against a brute-force double sum, the closed forms below and FEM convergence.

#include <vector>

namespace microdex::fem {

struct NavierDomain {
  double length_x_m = 0.20;  // L
  double length_y_m = 0.20;  // B
  double shear_modulus_Pa = 1.0e4;
  double thickness_m = 0.01;
};

// Uniform line load q on y = y₁, x₁ < x < x₂ (A.5).
struct UniformLineLoad {
  double x1_m = 0;
  double x2_m = 0;
  double y1_m = 0;
  double q_N_per_m = 0;
};

// (A.11) literally: the double series truncated at m_terms × n_terms.
double NavierDoubleSeries_m(const NavierDomain& domain, const UniformLineLoad& load, double x_m,
                            double y_m, int m_terms, int n_terms);

// The same series with the sum over n done in closed form (the 1-D Green's function
// Σ_n (2/B) sin(nπy/B) sin(nπη/B) / (k² + (nπ/B)²) = sinh(k y<) sinh(k(B − y>)) / (k sinh kB)),
// then summed over m until the remaining terms are below rel_tol of the sum (they decay like
// exp(−mπ|y − y₁|/L), so a point on the load line itself converges only algebraically and is
// capped at max_terms). *terms_used gets the number of m terms.
double NavierLineLoadDisplacement_m(const NavierDomain& domain, const UniformLineLoad& load,
                                    double x_m, double y_m, double rel_tol = 1e-12,
                                    int max_terms = 1000000, int* terms_used = nullptr);

// A point load of 1 N at (ξ, η): the displacement at (x, y) per newton, the Green's function
// of the rectangle. The Navier series with its sum over m done in closed form (roles of x and
// y swapped against the line load's):
//   w = Σ_n 2 sin(kη) sin(ky) sinh(k x<) sinh(k(L − x>)) / (G t B k sinh kL),  k = nπ/B,
// whose terms fall like exp(−k|x − ξ|): geometric off the line x = ξ (logarithmic at the load
// itself, which it does not take: x ≠ ξ is required, else NaN).
double NavierPointLoadDisplacement_m_per_N(const NavierDomain& domain, double xi_m, double eta_m,
                                           double x_m, double y_m);

// The line load q(x) on the bar y = y₁, x₁ < x < x₂ for which the Navier solution has
// w = w_bar all along the bar (the thesis's study presses a bar down 1 cm). q has inverse
// square-root singularities at the bar ends, so it is expanded as
//   q(x) = (1/a) Σ_l c_l T_l(s) / √(1 − s²),  x = x_c + a s,
// and solved by Galerkin: the kernel is the Navier series, whose m-sum splits exactly into the
// strip kernel (1/2π) ln|sin(π(x+ξ)/2L) / sin(π(x−ξ)/2L)| (the m-sum of the large-m limit of
// each term, closed form) plus a remainder summed term by term until it changes by < 1e-12
// relative; the logarithm is integrated exactly against the Chebyshev weight, the smooth rest
// by Gauss–Chebyshev quadrature.
class NavierBar {
 public:
  NavierBar(const NavierDomain& domain, double x1_m, double x2_m, double y1_m, double w_bar_m,
            int num_modes = 40, int max_series_terms = 4096);

  double TotalForce_N() const;                   // ∫ q dx: force of the tool on the tissue
  double LoadDensity_N_per_m(double x_m) const;  // q(x) (infinite at the ends)
  // ∫ q φ dx with φ the hat function of a node at x_node with spacing h (what an FEM
  // reaction (3.12) at that node converges to), and ∫ q over [xa, xb].
  double HatForce_N(double x_node_m, double h_m) const;
  double IntervalForce_N(double xa_m, double xb_m) const;
  // w at a point of the bar from the solved load (equals w_bar up to the solution error).
  double BarDisplacement_m(double x_m) const;
  // w anywhere off the bar's line y = y₁ (the series converges like exp(−mπ|y − y₁|/L)),
  // summed until the remaining terms are below 1e-12 of the sum or max_series_terms is hit.
  double Displacement_m(double x_m, double y_m) const;
  const std::vector<double>& coefficients() const { return c_; }
  int remainder_terms() const { return remainder_terms_; }

 private:
  double SmoothKernel(double x_m, double xi_m) const;  // G t · g − (−ln|x − ξ| / 2π)
  double LinearIntegral(double xa_m, double xb_m, double alpha, double beta) const;

  NavierDomain domain_;
  double x1_m_, x2_m_, y1_m_, w_bar_m_;
  double xc_m_, a_m_;
  std::vector<double> c_;
  std::vector<double> load_sine_;  // [m − 1] Σ_l c_l ∫ sin(mπξ/L) T_l(s)/√(1 − s²) ds
  int remainder_terms_ = 0;
};

}  // namespace microdex::fem
