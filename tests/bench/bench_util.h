#pragma once
// Small helpers shared by the reports: those that run the apps as processes (net, record,
// device), and the quantiles and the progress line of the in-process ones.

#include <chrono>
#include <string>
#include <vector>

namespace microdex::bench {

// The folder of the running microdex-bench (where the apps are built beside it).
std::string SelfDir();

// The number after `"key":` in a flat JSON text (an app's --score-out); NaN when absent.
double JsonNumber(const std::string& json, const std::string& key);

// The whole text of a file ("" when it cannot be read).
std::string ReadText(const std::string& path);

// The q-quantile of v (the element at floor(q n), clamped; 0 for none).
double Percentile(std::vector<double> v, double q);

// On a terminal only: "[done/total] what, ETA s" on standard error, the line ended at the end.
void Progress(const char* what, int done, int total, std::chrono::steady_clock::time_point start);

// The same line for a report of `total` steps that counts them itself: Step(what) after each;
// the line is cleared by Finish() or at destruction.
class ProgressLine {
 public:
  explicit ProgressLine(int total);
  ~ProgressLine() { Finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  void Step(const std::string& what);
  void Finish();

 private:
  int total_ = 0, done_ = 0;
  bool tty_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// Median over repetitions of the mean time per query (ns); a repetition calls fn(i) for every
// i < queries. Slow methods get fewer repetitions (at least 3) within budget_s.
template <typename Fn>
double MedianNsPerQuery(int queries, int reps, double budget_s, Fn&& fn) {
  std::vector<double> per_rep;
  const auto start = std::chrono::steady_clock::now();
  for (int rep = 0; rep < reps; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < queries; ++i) fn(i);
    const auto t1 = std::chrono::steady_clock::now();
    per_rep.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / queries);
    if (rep >= 2 && std::chrono::duration<double>(t1 - start).count() > budget_s) break;
  }
  return Percentile(per_rep, 0.5);
}

}  // namespace microdex::bench
