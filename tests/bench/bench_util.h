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

}  // namespace microdex::bench
