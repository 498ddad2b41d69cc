// Runs `microdex-bench loop_wire` as a user would: the --quick JSON report's shape and the
// exact query's error in it, and bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace microdex::bench {
namespace {

std::string Bench() {
  const char* dir = std::getenv("MICRODEX_BIN_DIR");
  return dir == nullptr ? std::string(MICRODEX_LOOP_WIRE_BENCH_EXE)
                        : std::string(dir) + "/microdex-bench";
}

int RunBench(const std::string& args) {
  const std::string cmd = Bench() + " loop_wire " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The number after `"key": ` at or after position `from`.
double NumberAfter(const std::string& s, const std::string& key, std::size_t from) {
  const std::size_t at = s.find("\"" + key + "\": ", from);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(s.c_str() + at + key.size() + 4, nullptr);
}

TEST(LoopWireBenchCli, QuickJsonReport) {
  const std::string json = ::testing::TempDir() + "/loop_wire_bench_cli.json";
  ASSERT_EQ(RunBench("--quick --queries 40 --reps 1 --json '" + json + "'"), 0);
  const std::string s = ReadAll(json);
  for (const char* key : {"\"families\"", "\"threaded\"", "\"far\"", "\"sampled\"",
                          "\"mesh (FCL)\"", "\"segment_quartic_check\""}) {
    EXPECT_NE(s.find(key), std::string::npos) << key;
  }
  // The exact query's error against the long-double reference, in both families: far below
  // 1e-12 R (R = 2 mm).
  int exact_entries = 0;
  for (std::size_t at = s.find("\"method\": \"exact\""); at != std::string::npos;
       at = s.find("\"method\": \"exact\"", at + 1)) {
    ++exact_entries;
    const double err = NumberAfter(s, "max_error_m", at);
    EXPECT_GE(err, 0);
    EXPECT_LT(err, 2e-15);
    EXPECT_EQ(NumberAfter(s, "contact_agreement", at), 1.0);
  }
  EXPECT_EQ(exact_entries, 2);
}

TEST(LoopWireBenchCli, BadInputExitsTwo) {
  EXPECT_EQ(RunBench("--queries 0"), 2);
  EXPECT_EQ(RunBench("--no-such-option"), 2);
  EXPECT_EQ(RunBench("--quick --queries 10 --json /nonexistent-dir/x.json"), 2);
}

}  // namespace
}  // namespace microdex::bench
