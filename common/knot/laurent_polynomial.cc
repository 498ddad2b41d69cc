#include "common/knot/laurent_polynomial.h"

#include <algorithm>
#include <cstdlib>
#include <utility>

#include "common/base/check.h"

namespace microdex::knot {

LaurentPolynomial MakePolynomial(int min_power, std::vector<std::int64_t> coefficients) {
  return Trimmed(LaurentPolynomial{min_power, std::move(coefficients)});
}

LaurentPolynomial Trimmed(LaurentPolynomial p) {
  auto& c = p.coefficients;
  std::size_t first = 0;
  while (first < c.size() && c[first] == 0) ++first;
  if (first == c.size()) return LaurentPolynomial{0, {}};
  std::size_t last = c.size();
  while (c[last - 1] == 0) --last;
  p.min_power += static_cast<int>(first);
  c = std::vector<std::int64_t>(c.begin() + static_cast<std::ptrdiff_t>(first),
                                c.begin() + static_cast<std::ptrdiff_t>(last));
  return p;
}

LaurentPolynomial Multiply(const LaurentPolynomial& a, const LaurentPolynomial& b) {
  if (a.coefficients.empty() || b.coefficients.empty()) return LaurentPolynomial{0, {}};
  LaurentPolynomial r{a.min_power + b.min_power,
                      std::vector<std::int64_t>(a.coefficients.size() + b.coefficients.size() - 1)};
  for (std::size_t i = 0; i < a.coefficients.size(); ++i) {
    for (std::size_t j = 0; j < b.coefficients.size(); ++j) {
      r.coefficients[i + j] += a.coefficients[i] * b.coefficients[j];
    }
  }
  return Trimmed(std::move(r));
}

LaurentPolynomial Add(const LaurentPolynomial& a, const LaurentPolynomial& b) {
  if (a.coefficients.empty()) return b;
  if (b.coefficients.empty()) return a;
  const int lo = std::min(a.min_power, b.min_power);
  const int hi = std::max(a.min_power + static_cast<int>(a.coefficients.size()),
                          b.min_power + static_cast<int>(b.coefficients.size()));
  LaurentPolynomial r{lo, std::vector<std::int64_t>(hi - lo, 0)};
  for (std::size_t i = 0; i < a.coefficients.size(); ++i) {
    r.coefficients[a.min_power - lo + static_cast<int>(i)] += a.coefficients[i];
  }
  for (std::size_t i = 0; i < b.coefficients.size(); ++i) {
    r.coefficients[b.min_power - lo + static_cast<int>(i)] += b.coefficients[i];
  }
  return Trimmed(std::move(r));
}

LaurentPolynomial Mirror(const LaurentPolynomial& p) {
  if (p.coefficients.empty()) return p;
  LaurentPolynomial r{-(p.min_power + static_cast<int>(p.coefficients.size()) - 1),
                      std::vector<std::int64_t>(p.coefficients.rbegin(), p.coefficients.rend())};
  return r;
}

std::int64_t EvaluateAtPlusMinusOne(const LaurentPolynomial& p, int x) {
  MICRODEX_CHECK(x == 1 || x == -1);
  std::int64_t sum = 0;
  for (std::size_t i = 0; i < p.coefficients.size(); ++i) {
    const int power = p.min_power + static_cast<int>(i);
    sum += (x == -1 && (power % 2 != 0)) ? -p.coefficients[i] : p.coefficients[i];
  }
  return sum;
}

std::string ToString(const LaurentPolynomial& p, const char* variable) {
  if (p.coefficients.empty()) return "0";
  std::string out;
  for (std::size_t i = 0; i < p.coefficients.size(); ++i) {
    const std::int64_t c = p.coefficients[i];
    if (c == 0) continue;
    const int power = p.min_power + static_cast<int>(i);
    if (out.empty()) {
      if (c < 0) out += "-";
    } else {
      out += c < 0 ? " - " : " + ";
    }
    const std::int64_t mag = std::llabs(c);
    if (mag != 1 || power == 0) out.append(std::to_string(mag));
    if (power != 0) {
      out.append(variable);
      if (power != 1) {
        out.push_back('^');
        out.append(std::to_string(power));
      }
    }
  }
  return out;
}

}  // namespace microdex::knot
