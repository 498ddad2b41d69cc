#pragma once
// Laurent polynomials with integer coefficients, the values of the knot invariants
// (Alexander in t, Jones in t).

#include <cstdint>
#include <string>
#include <vector>

namespace microdex::knot {

// A Laurent polynomial with integer coefficients: sum_k coefficients[k] * x^(min_power + k).
struct LaurentPolynomial {
  int min_power = 0;
  std::vector<std::int64_t> coefficients;
  bool operator==(const LaurentPolynomial&) const = default;
};

LaurentPolynomial MakePolynomial(int min_power, std::vector<std::int64_t> coefficients);
// Strips zero coefficients at both ends; the zero polynomial is {0, {}}.
LaurentPolynomial Trimmed(LaurentPolynomial p);
LaurentPolynomial Multiply(const LaurentPolynomial& a, const LaurentPolynomial& b);
LaurentPolynomial Add(const LaurentPolynomial& a, const LaurentPolynomial& b);
// p(x) -> p(1/x): the invariant of the mirror image for the Jones polynomial.
LaurentPolynomial Mirror(const LaurentPolynomial& p);
// Value at an integer point (|x| = 1 for negative powers to stay exact).
std::int64_t EvaluateAtPlusMinusOne(const LaurentPolynomial& p, int x);
// E.g. "t^-1 - 1 + t".
std::string ToString(const LaurentPolynomial& p, const char* variable = "t");

}  // namespace microdex::knot
