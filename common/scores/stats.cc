#include "common/scores/stats.h"

#include <array>
#include <cmath>

namespace microdex::scores {

MeanCi CalcMeanCi(std::span<const double> x) {
  MeanCi r;
  r.n = static_cast<int>(x.size());
  if (x.empty()) {
    r.mean = r.lo = r.hi = NAN;
    return r;
  }
  double sum = 0;
  for (double v : x) sum += v;
  r.mean = sum / r.n;
  r.lo = r.hi = r.mean;
  if (r.n < 2) return r;
  double ss = 0;
  for (double v : x) ss += (v - r.mean) * (v - r.mean);
  r.sd = std::sqrt(ss / (r.n - 1));
  const double half = StudentT975(r.n - 1) * r.sd / std::sqrt(static_cast<double>(r.n));
  r.lo = r.mean - half;
  r.hi = r.mean + half;
  return r;
}

double StudentT975(int df) {
  // Exact to the digits shown for df 1..30 (standard tables); beyond, the Cornish-Fisher
  // expansion z + (z³ + z) / (4 df) + (5z⁵ + 16z³ + 3z) / (96 df²), within 1e-4 there.
  static constexpr std::array<double, 30> kTable = {
      12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281,
      2.2010,  2.1788, 2.1604, 2.1448, 2.1314, 2.1199, 2.1098, 2.1009, 2.0930, 2.0860,
      2.0796,  2.0739, 2.0687, 2.0639, 2.0595, 2.0555, 2.0518, 2.0484, 2.0452, 2.0423};
  if (df < 1) return NAN;
  if (df <= 30) return kTable[static_cast<std::size_t>(df - 1)];
  const double z = 1.959963984540054, n = df;
  return z + (z * z * z + z) / (4 * n) +
         (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * n * n);
}

EffectSize CalcHedgesG(std::span<const double> group1, std::span<const double> group2) {
  EffectSize e;
  const MeanCi a = CalcMeanCi(group1), b = CalcMeanCi(group2);
  e.n1 = a.n;
  e.n2 = b.n;
  if (a.n < 2 || b.n < 2) {
    e.g = e.lo = e.hi = NAN;
    return e;
  }
  const double n1 = a.n, n2 = b.n;
  const double s_pooled =
      std::sqrt(((n1 - 1) * a.sd * a.sd + (n2 - 1) * b.sd * b.sd) / (n1 + n2 - 2));
  if (!(s_pooled > 0)) {
    e.g = e.lo = e.hi = NAN;
    return e;
  }
  const double d = (a.mean - b.mean) / s_pooled;
  const double j = 1 - 3 / (4 * (n1 + n2) - 9);  // small-sample correction
  e.g = j * d;
  const double se = std::sqrt((n1 + n2) / (n1 * n2) + e.g * e.g / (2 * (n1 + n2)));
  e.lo = e.g - 1.959963984540054 * se;
  e.hi = e.g + 1.959963984540054 * se;
  return e;
}

}  // namespace microdex::scores
