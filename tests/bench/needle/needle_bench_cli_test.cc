// Runs `microdex-bench needle` as a user would: --cases on analytic cases, malformed input,
// and the --quick JSON report's shape.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace microdex::bench {
namespace {

// Absolute, for a 5 mm core radius: 1e-12 relative.
constexpr double kExactTol_m = 5e-15;
// The SP column is held to the touch / no-touch agreement and a looser clearance bound.
constexpr double kSpTol_m = 5e-12;

std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v == nullptr ? std::string() : std::string(v);
}

std::string Bench() {
  const std::string dir = Env("MICRODEX_BIN_DIR");
  return dir.empty() ? std::string(MICRODEX_NEEDLE_BENCH_EXE) : dir + "/microdex-bench";
}
std::string Source() {
  const std::string dir = Env("MICRODEX_SOURCE_DIR");
  return dir.empty() ? std::string(MICRODEX_NEEDLE_SOURCE_DIR) : dir;
}
std::string Tmp(const std::string& name) {
  return ::testing::TempDir() + "/needle_bench_cli_" + name;
}

int RunBench(const std::string& args, const std::string& stderr_file) {
  const std::string cmd = Bench() + " " + args + " 2> '" + stderr_file + "'";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::vector<std::string>> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST(NeedleBenchCli, CasesGiveTheAnalyticClearances) {
  ASSERT_FALSE(Source().empty());
  const std::string out = Tmp("cases_out.csv"), err = Tmp("cases_err.txt");
  ASSERT_EQ(
      RunBench("needle --cases '" + Source() + "/tests/data/needle_cases.csv' --out '" + out + "'",
               err),
      0)
      << ReadAll(err);
  const auto got = ReadCsv(out);
  const auto expected = ReadCsv(Source() + "/tests/data/needle_cases_expected.csv");
  ASSERT_EQ(got.size(), expected.size());
  ASSERT_EQ(got[0], (std::vector<std::string>{"sp_clearance", "exact_clearance", "sp_contact",
                                              "exact_contact"}));
  for (size_t i = 1; i < got.size(); ++i) {
    ASSERT_EQ(got[i].size(), 4u) << "row " << i;
    const std::string& what = expected[i][2];
    if (expected[i][0] == "nan") {
      EXPECT_EQ(got[i][0], "nan") << what;
      EXPECT_EQ(got[i][1], "nan") << what;
      EXPECT_EQ(got[i][2], "0") << what;
      EXPECT_EQ(got[i][3], "0") << what;
      continue;
    }
    const double want = std::stod(expected[i][0]);
    EXPECT_NEAR(std::stod(got[i][1]), want, kExactTol_m) << what;
    EXPECT_EQ(got[i][3], expected[i][1]) << what;
    EXPECT_NEAR(std::stod(got[i][0]), want, kSpTol_m) << what;
    EXPECT_EQ(got[i][2], expected[i][1]) << what;
  }
}

TEST(NeedleBenchCli, MalformedCasesExitTwoNamingFileAndLine) {
  const std::string in = Tmp("bad_cases.csv"), out = Tmp("bad_out.csv"), err = Tmp("bad_err.txt");
  {
    std::ofstream f(in);
    f << "nx,ny,nz,nqw,nqx,nqy,nqz,needle_radius,needle_sweep,tx,ty,tz,tqw,tqx,tqy,tqz,R,r,"
         "segment_angle\n"
      << "0,0,0,1,0,0,0,0.005,1.5,0,0,0,1,0,0,0,0.005,0.0005,6.28\n"
      << "0,0,0,1,0,0,0,0.005,abc,0,0,0,1,0,0,0,0.005,0.0005,6.28\n";
  }
  EXPECT_EQ(RunBench("needle --cases '" + in + "' --out '" + out + "'", err), 2);
  const std::string message = ReadAll(err);
  EXPECT_NE(message.find(in + ":3"), std::string::npos) << message;
  EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << message;
  {
    std::ofstream f(in);
    f << "nx,ny,nz\n1,2,3\n";
  }
  EXPECT_EQ(RunBench("needle --cases '" + in + "' --out '" + out + "'", err), 2);
  EXPECT_NE(ReadAll(err).find(in + ":1"), std::string::npos) << ReadAll(err);
  {
    std::ofstream f(in);
    f << "nx,ny,nz,nqw,nqx,nqy,nqz,needle_radius,needle_sweep,tx,ty,tz,tqw,tqx,tqy,tqz,R,r,"
         "segment_angle\n"
      << "0,0,0,1,0,0,0,0.005,1.5,0,0,0,1,0,0,0,0.005,0.006,6.28\n";
  }
  EXPECT_EQ(RunBench("needle --cases '" + in + "' --out '" + out + "'", err), 2);
  EXPECT_NE(ReadAll(err).find("tube_radius_m"), std::string::npos) << ReadAll(err);
  EXPECT_EQ(RunBench("needle --cases '" + Tmp("missing.csv") + "' --out '" + out + "'", err), 2);
}

TEST(NeedleBenchCli, QuickJsonReportHasTheDocumentedShape) {
  const std::string json = Tmp("report.json"), err = Tmp("report_err.txt");
  ASSERT_EQ(RunBench("needle --quick --json '" + json + "' --mesh-dir '" + ::testing::TempDir() +
                         "/needle_meshes'",
                     err),
            0)
      << ReadAll(err);
  const std::string all_text = ReadAll(json);
  // The headline family's table comes first; every family follows with its own.
  const size_t families_at = all_text.find("\"families\": [");
  ASSERT_NE(families_at, std::string::npos) << all_text;
  const std::string text = all_text.substr(0, families_at);
  const std::string families = all_text.substr(families_at);
  const std::regex method(
      R"re(\{"name": "(sp|exact|sampling|mesh|sp_thesis)", "setting": "[^"]*", "ns_per_query": [0-9.e+-]+, "max_abs_error": [0-9.e+-]+, "rms_error": [0-9.e+-]+, "agreement": [0-9.e+-]+)re");
  int count[5] = {0, 0, 0, 0, 0};
  const char* names[5] = {"sp", "exact", "sampling", "mesh", "sp_thesis"};
  for (auto it = std::sregex_iterator(text.begin(), text.end(), method);
       it != std::sregex_iterator(); ++it) {
    for (int k = 0; k < 5; ++k) count[k] += (*it)[1] == names[k];
  }
  EXPECT_EQ(count[0], 1) << text;  // the default path
  EXPECT_GE(count[4], 2) << text;  // the thesis's pass at several quartic tolerances
  EXPECT_EQ(count[1], 1) << text;
  EXPECT_GE(count[2], 5) << text;
  EXPECT_GE(count[3], 2) << text;
  EXPECT_TRUE(std::regex_search(
      text,
      std::regex(
          R"re("ratios": \{"mesh_over_sp": ([0-9.e+-]+|null), "sampling_over_sp": ([0-9.e+-]+|null), "exact_over_sp": ([0-9.e+-]+|null)\})re")))
      << text;
  // The exact method is the reference: its own error is zero and it agrees everywhere.
  const std::regex exact_line(
      R"re("name": "exact", "setting": "closed form", "ns_per_query": [0-9.e+-]+, "max_abs_error": 0, "rms_error": 0, "agreement": 1)re");
  EXPECT_TRUE(std::regex_search(text, exact_line)) << text;
  // Four families, each with its ratios, goal checks and its own exact line.
  const std::regex family_ratios(
      R"re("ratios": \{"mesh_over_sp": ([0-9.e+-]+|null), "sampling_over_sp": ([0-9.e+-]+|null), "exact_over_sp": ([0-9.e+-]+|null)\})re");
  const auto count_matches = [&](const std::regex& re) {
    return std::distance(std::sregex_iterator(families.begin(), families.end(), re),
                         std::sregex_iterator());
  };
  EXPECT_EQ(count_matches(family_ratios), 4) << families;
  EXPECT_EQ(count_matches(exact_line), 4) << families;
  EXPECT_EQ(count_matches(std::regex(R"re("goals": \[\{"goal": )re")), 4) << families;
  // The deepest-point error: zero for the reference itself, and counted per family.
  EXPECT_EQ(
      count_matches(std::regex(
          R"re("name": "exact", "setting": "closed form", [^}]*"max_point_error": 0, "point_queries": [0-9]+)re")),
      4)
      << families;
  EXPECT_EQ(count_matches(std::regex(R"re("point_ratios": \{"mesh_over_sp": )re")), 4) << families;
  EXPECT_EQ(count_matches(std::regex(R"re("lower_bounds": \[("[a-z_ ()]+"(, )?)*\])re")), 4)
      << families;
  // The default path's error against the exact method in every family: README.md states
  // ≤ 8.4e-17 m on the full run (R = 5 mm), held here as ≤ 1e-16 m.
  const std::regex default_error(
      R"re("name": "sp", "setting": "clip\+ascent\+certificate \(default\)", "ns_per_query": [0-9.e+-]+, "max_abs_error": ([0-9.e+-]+))re");
  int default_rows = 0;
  for (auto it = std::sregex_iterator(families.begin(), families.end(), default_error);
       it != std::sregex_iterator(); ++it) {
    EXPECT_LE(std::stod((*it)[1]), 1e-16) << it->str();
    ++default_rows;
  }
  EXPECT_EQ(default_rows, 4) << families;
  // Which stage settled each default query: the counts of every family add up to its queries.
  const std::regex decisions(
      R"re("queries": ([0-9]+), "contacts"(?:[^\n]*\n){3} *"sp_decisions": \{"invalid_input": ([0-9]+), "empty_range": ([0-9]+), "thesis_pass": ([0-9]+), "quick_certificate": ([0-9]+), "lifted_certificate": ([0-9]+), "along_needle": ([0-9]+), "rounds_exhausted": ([0-9]+), "exact": ([0-9]+)\})re");
  int families_with_decisions = 0;
  for (auto it = std::sregex_iterator(families.begin(), families.end(), decisions);
       it != std::sregex_iterator(); ++it) {
    int sum = 0;
    for (int k = 2; k <= 9; ++k) sum += std::stoi((*it)[k]);
    EXPECT_EQ(sum, std::stoi((*it)[1])) << it->str();
    EXPECT_EQ(std::stoi((*it)[4]), 0) << "the default path has the certificate: " << it->str();
    EXPECT_GT(std::stoi((*it)[5]), 0) << "the quick test settles most queries: " << it->str();
    ++families_with_decisions;
  }
  EXPECT_EQ(families_with_decisions, 4) << families;
  EXPECT_EQ(count_matches(std::regex(R"re("met": (true|false))re")),
            4 + 3 * 3)  // the mesh goal only where the mesh answers
      << families;
}

}  // namespace
}  // namespace microdex::bench
