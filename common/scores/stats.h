#pragma once
// The statistics of the experiment report: mean with a 95 % confidence interval (Student t)
// and Hedges' g between two groups with its 95 % confidence interval (the large-sample normal
// approximation of Hedges & Olkin 1985, eq. 5.15: var(g) = (n1 + n2) / (n1 n2) + g² / (2 (n1 +
// n2))). Pure functions, no I/O.

#include <span>

namespace microdex::scores {

struct MeanCi {
  int n = 0;
  double mean = 0;
  double sd = 0;          // sample standard deviation (n − 1); 0 for n < 2
  double lo = 0, hi = 0;  // 95 % CI of the mean; the mean itself for n < 2
};
MeanCi CalcMeanCi(std::span<const double> x);

// The two-sided 95 % quantile of Student's t with `df` degrees of freedom (df >= 1).
double StudentT975(int df);

struct EffectSize {
  int n1 = 0, n2 = 0;
  double g = 0;           // Hedges' g of group 1 against group 2: (m1 − m2) / s_pooled · J
  double lo = 0, hi = 0;  // 95 % CI
};
// NaN g (and CI) when a group has fewer than two values or both have no spread.
EffectSize CalcHedgesG(std::span<const double> group1, std::span<const double> group2);

}  // namespace microdex::scores
