#include "station/period_stats.h"

#include <algorithm>
#include <cmath>

namespace microdex::station {

void PeriodStats::Add(std::int64_t period_ns) {
  if (period_ns < 0) period_ns = 0;
  const std::int64_t bin = period_ns / kBin_ns;
  if (bin < kBins) {
    ++bins_[static_cast<std::size_t>(bin)];
  } else {
    long_ns_.push_back(period_ns);
  }
  ++count_;
  sum_ns_ += static_cast<double>(period_ns);
  max_ns_ = std::max(max_ns_, period_ns);
}

double PeriodStats::Quantile_s(double q) const {
  if (count_ == 0) return 0;
  // Rank of the quantile sample, 1-based: the smallest value with at least q·n samples <= it.
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += bins_[static_cast<std::size_t>(b)];
    if (seen >= rank) return static_cast<double>((b + 1) * kBin_ns) * 1e-9;
  }
  std::vector<std::int64_t> sorted = long_ns_;
  std::sort(sorted.begin(), sorted.end());
  const std::uint64_t i = std::min<std::uint64_t>(rank - seen - 1, sorted.size() - 1);
  return static_cast<double>(sorted[i]) * 1e-9;
}

void PeriodStats::Reset() {
  std::fill(bins_.begin(), bins_.end(), 0);
  long_ns_.clear();
  count_ = 0;
  sum_ns_ = 0;
  max_ns_ = 0;
}

}  // namespace microdex::station
