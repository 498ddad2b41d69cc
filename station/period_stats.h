#pragma once
// Statistics of the haptic period (time between consecutive tick starts) over a whole run:
// a histogram with 1 µs bins up to 20 ms (longer periods are kept exactly), so that p99 and
// p99.9 are exact to 1 µs. Lives in the publisher thread, never in the haptic thread.

#include <cstdint>
#include <vector>

namespace microdex::station {

class PeriodStats {
 public:
  static constexpr std::int64_t kBin_ns = 1000;
  static constexpr int kBins = 20000;

  PeriodStats() : bins_(kBins, 0) {}
  void Add(std::int64_t period_ns);
  std::uint64_t count() const { return count_; }
  double mean_s() const { return count_ ? sum_ns_ / static_cast<double>(count_) * 1e-9 : 0; }
  double max_s() const { return static_cast<double>(max_ns_) * 1e-9; }
  // The q-quantile (0 < q < 1), s: the upper edge of the bin holding it.
  double Quantile_s(double q) const;
  void Reset();

 private:
  std::vector<std::uint32_t> bins_;
  std::vector<std::int64_t> long_ns_;
  std::uint64_t count_ = 0;
  double sum_ns_ = 0;
  std::int64_t max_ns_ = 0;
};

}  // namespace microdex::station
