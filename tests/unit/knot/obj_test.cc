// OBJ polylines (common/knot/obj): round trip, the forms of `l` elements exporters
// write, and one-line errors naming the file and the line.
#include "common/knot/obj.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace microdex::knot {
namespace {

std::filesystem::path WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("microdex_knot_obj_" + name);
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::filesystem::path& path) {
  try {
    ReadObjPolyline(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(KnotObjTest, RoundTrip) {
  const std::vector<Eigen::Vector3d> nodes = {{0, 0, 0}, {1e-5, 2e-5, -3e-5}, {4.25, -1, 0.5}};
  const auto path = std::filesystem::temp_directory_path() / "microdex_knot_obj_roundtrip.obj";
  WriteObjPolyline(path, nodes, {"three nodes"});
  const auto read = ReadObjPolyline(path);
  ASSERT_EQ(read.size(), nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    EXPECT_LT((read[i] - nodes[i]).norm(), 1e-8 * (1.0 + nodes[i].norm()));
  }
}

TEST(KnotObjTest, TheThreadDiameterTravelsAsItsOwnComment) {
  const std::vector<Eigen::Vector3d> nodes = {{0, 0, 0}, {1e-4, 0, 0}, {2e-4, 0, 0}};
  const auto path = std::filesystem::temp_directory_path() / "microdex_knot_obj_diameter.obj";
  WriteObjPolyline(path, nodes, {"a comment"}, 2.5e-5);
  double d = -1;
  EXPECT_EQ(ReadObjPolyline(path, &d).size(), 3u);
  EXPECT_DOUBLE_EQ(d, 2.5e-5);
  // Without one, 0; a comment that only mentions it is not it.
  WriteObjPolyline(path, nodes, {"the thread_diameter_m 3e-5 line is absent"});
  EXPECT_EQ(ReadObjPolyline(path, &d).size(), 3u);
  EXPECT_EQ(d, 0.0);
  // A malformed one names the file and the line.
  for (const char* bad : {"# thread_diameter_m\n", "# thread_diameter_m -1e-5\n",
                          "# thread_diameter_m nan\n", "# thread_diameter_m 2e-5 m\n"}) {
    const auto bad_path =
        WriteTemp("bad_diameter.obj", std::string("v 0 0 0\n") + bad + "v 1 0 0\nl 1 2\n");
    const std::string e = ErrorOf(bad_path);
    EXPECT_NE(e.find("bad_diameter.obj:2: malformed '# thread_diameter_m D'"), std::string::npos)
        << bad << ": " << e;
  }
}

// A corrupt file (bytes replaced, dropped or repeated anywhere in a valid one, the diameter
// line included) is read or refused with an error naming it; nothing else escapes.
TEST(KnotObjTest, CorruptFilesAreReadOrRefusedByName) {
  const std::vector<Eigen::Vector3d> nodes = {{0, 0, 1e-4}, {1e-4, 0, -1e-4}, {2e-4, 0, 1e-4}};
  const auto path = std::filesystem::temp_directory_path() / "microdex_knot_obj_corrupt.obj";
  WriteObjPolyline(path, nodes, {"seed"}, 2.5e-5);
  std::ifstream in(path);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::mt19937 rng(7);
  const std::string alphabet = "v l#-+.e0123456789/ \n\r\tnaNinf_thread_diameter_m";
  int refused = 0, read = 0;
  for (int k = 0; k < 2000; ++k) {
    std::string text = good;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = rng() % text.size();
      switch (rng() % 3) {
        case 0:
          text[at] = alphabet[rng() % alphabet.size()];
          break;
        case 1:
          text.erase(at, 1 + rng() % 8);
          break;
        default:
          text.insert(at, text.substr(at, 1 + rng() % 16));
          break;
      }
    }
    std::ofstream(path, std::ios::trunc) << text;
    try {
      double d = 0;
      const std::vector<Eigen::Vector3d> p = ReadObjPolyline(path, &d);
      EXPECT_GE(p.size(), 2u);
      EXPECT_TRUE(d == 0.0 || (std::isfinite(d) && d > 0)) << d;
      ++read;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("microdex_knot_obj_corrupt.obj"), std::string::npos)
          << e.what();
      ++refused;
    }
  }
  EXPECT_GT(refused, 100);
  EXPECT_GT(read, 100);
}

TEST(KnotObjTest, ExporterForms) {
  // One element per segment, out of order and reversed, with v/vt forms, negative indices,
  // CRLF line ends and unrelated statements.
  const auto path = WriteTemp("forms.obj",
                              "o thread\r\nv 0 0 0\r\nv 1 0 0\r\nv 2 0 0\r\nv 3 0 0\r\n"
                              "vt 0 0\r\nl 2/1 3/1\r\nl 2 1\r\nl -2 -1\r\ns off\r\n");
  const auto nodes = ReadObjPolyline(path);
  ASSERT_EQ(nodes.size(), 4u);
  // The chain runs 1-2-3-4 or its reverse.
  const double first_x = nodes.front().x();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    EXPECT_DOUBLE_EQ(nodes[i].x(), first_x == 0.0 ? double(i) : 3.0 - double(i));
  }
}

TEST(KnotObjTest, ErrorsNameFileAndLine) {
  EXPECT_NE(ErrorOf(WriteTemp("v.obj", "v 0 0 0\nv 1 nan_ 0\nl 1 2\n")).find("v.obj:2:"),
            std::string::npos);
  EXPECT_NE(ErrorOf(WriteTemp("short.obj", "v 0 0\nl 1 1\n")).find("short.obj:1:"),
            std::string::npos);
  EXPECT_NE(ErrorOf(WriteTemp("range.obj", "v 0 0 0\nv 1 0 0\nl 1 3\n")).find("range.obj:3:"),
            std::string::npos);
  EXPECT_NE(ErrorOf(WriteTemp("zero.obj", "v 0 0 0\nv 1 0 0\nl 0 1\n")).find("zero.obj:3:"),
            std::string::npos);
  EXPECT_NE(ErrorOf(WriteTemp("one.obj", "v 0 0 0\nl 1\n")).find("one.obj:2:"), std::string::npos);
  EXPECT_NE(ErrorOf(WriteTemp("none.obj", "v 0 0 0\nv 1 0 0\n")).find("no 'l' element"),
            std::string::npos);
  EXPECT_NE(ErrorOf(WriteTemp("apart.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nl 1 2\nl 3 4\n"))
                .find("apart.obj:6:"),
            std::string::npos);
  EXPECT_NE(ErrorOf("/nonexistent/microdex.obj").find("cannot open"), std::string::npos);
  // Every message is one line.
  EXPECT_EQ(ErrorOf(WriteTemp("v2.obj", "v 0 0 x\n")).find('\n'), std::string::npos);
}

}  // namespace
}  // namespace microdex::knot
