#pragma once
// Real roots of a polynomial of degree ≤ 4 inside a closed interval, for the extrema quartic
// (4.26) of the SP needle–vessel method.
//
// The thesis solves (4.26) by Newton iteration (§4.3). Plain Newton can miss roots or converge
// to the same root twice, so this isolates them first, without complex arithmetic: the roots
// of p'' (closed form) split the interval into pieces where p' is monotone, the roots of p'
// found there split it into pieces where p is monotone, and each piece whose ends have
// opposite signs holds exactly one root, found by Newton steps kept inside the bracket
// (bisection when a step leaves it). Leading coefficients that vanish are handled by the same
// cascade. A root of even multiplicity (p touches 0 without a sign change) is reported when p
// at the local extremum is within 1e-12 of the coefficients' size from 0: for the SP method a
// double root of (4.26) can be two distinct extrema of φ(θ), one on each sign of v.

namespace microdex::geometry {

struct PolyRootOptions {
  double tol = 1e-15;  // stop when the Newton step or the bracket is below this (absolute)
  int max_iters = 80;  // per root; bisection guarantees progress, Newton makes it quadratic
};

// p(t) = k[0] + k[1] t + k[2] t² + k[3] t³ + k[4] t⁴. Writes the real roots in [lo, hi] in
// increasing order to roots (room for 4) and returns their count. No allocation.
int FindPolyRootsInInterval(const double k[5], double lo, double hi, const PolyRootOptions& opt,
                            double roots[4]);

// The same roots from the closed form (Ferrari: depressed quartic, largest root of the
// resolvent cubic, two quadratics), each polished by newton_polish Newton steps on p. The
// result is checked: p must change sign across each root. When the check fails (a double or
// nearly double root, a vanishing leading coefficient that the closed form cannot resolve)
// the bracketed search above answers instead and *used_fallback is set.
int SolveQuarticInInterval(const double k[5], double lo, double hi, int newton_polish,
                           const PolyRootOptions& fallback, double roots[4], bool* used_fallback);

// p(t) by Horner.
inline double EvalPoly4(const double k[5], double t) {
  return (((k[4] * t + k[3]) * t + k[2]) * t + k[1]) * t + k[0];
}

}  // namespace microdex::geometry
