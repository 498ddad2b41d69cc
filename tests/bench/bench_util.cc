#include "bench_util.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>

namespace microdex::bench {

std::string SelfDir() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return ".";
  std::string p(buf, static_cast<std::size_t>(n));
  return p.substr(0, p.rfind('/'));
}

double JsonNumber(const std::string& json, const std::string& key) {
  const auto at = json.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + at + key.size() + 3, nullptr);
}

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

void Progress(const char* what, int done, int total, std::chrono::steady_clock::time_point start) {
  if (isatty(STDERR_FILENO) == 0) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double eta = done > 0 ? s * (total - done) / done : 0.0;
  std::fprintf(stderr, "\r[%d/%d] %s, ETA %.0f s   ", done, total, what, eta);
  if (done == total) std::fprintf(stderr, "\n");
}

ProgressLine::ProgressLine(int total) : total_(total), tty_(isatty(STDERR_FILENO) != 0) {}

void ProgressLine::Step(const std::string& what) {
  ++done_;
  if (!tty_) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double eta = s * (total_ - done_) / done_;
  std::fprintf(stderr, "\r[%d/%d] %-40s ETA %4.0f s   ", done_, total_, what.c_str(), eta);
}

void ProgressLine::Finish() {
  if (tty_) std::fprintf(stderr, "\r%*s\r", 72, "");
  tty_ = false;
}

}  // namespace microdex::bench
