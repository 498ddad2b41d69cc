// YamlReader: typed fields with defaults, and every bad-input error as
// "FILE:LINE: section.field: reason".
#include "common/base/yaml_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace microdex {
namespace {

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// The message of the InputError `f` throws ("" when it throws none).
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

enum class Colour { kRed, kBlue };

Colour ParseColour(const std::string& text) {
  if (text == "red") return Colour::kRed;
  if (text == "blue") return Colour::kBlue;
  throw std::invalid_argument("expected red or blue");
}

const char* kGood =
    "# a comment\n"            // 1
    "box:\n"                   // 2
    "  width_m: 0.5\n"         // 3
    "  count: 3\n"             // 4
    "  label: lid\n"           // 5
    "  open: true\n"           // 6
    "  corner_m: [1, 2, 3]\n"  // 7
    "  colour: blue\n"         // 8
    "  tags: [a, b]\n"         // 9
    "  inner:\n"               // 10
    "    depth_m: 0.1\n"       // 11
    "empty:\n";                // 12

TEST(YamlReader, ReadsFieldsAndKeepsDefaultsOfAbsentOnes) {
  const std::string path = Write("yaml_good.yaml", kGood);
  const YamlReader reader(path);
  EXPECT_EQ(reader.file(), path);
  const YamlSection box = reader.Root().Map("box");
  EXPECT_EQ(box.Field("count"), "box.count");
  EXPECT_DOUBLE_EQ(box.Double("width_m", 0), 0.5);
  EXPECT_DOUBLE_EQ(box.FiniteDouble("height_m", 7), 7);
  EXPECT_TRUE(std::isnan(box.FiniteDouble("height_m", std::nan(""))));
  EXPECT_EQ(box.Int("count", 0), 3);
  EXPECT_EQ(box.Int("rows", 9), 9);
  EXPECT_EQ(box.String("label", ""), "lid");
  EXPECT_TRUE(box.Bool("open", false));
  EXPECT_FALSE(box.Bool("closed", false));
  EXPECT_EQ(box.Vec3("corner_m", Eigen::Vector3d::Zero()), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(box.Vec3("origin_m", Eigen::Vector3d::Ones()), Eigen::Vector3d::Ones());
  EXPECT_EQ(box.Enum("colour", &ParseColour, Colour::kRed), Colour::kBlue);
  EXPECT_EQ(box.Enum("shade", &ParseColour, Colour::kRed), Colour::kRed);
  EXPECT_EQ(box.StringList("tags"), (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(box.StringList("notes").empty());
  EXPECT_TRUE(box.Has("inner"));
  EXPECT_FALSE(box.Has("outer"));
  EXPECT_DOUBLE_EQ(box.Map("inner").Double("depth_m", 0), 0.1);
  EXPECT_FALSE(reader.Root().OptionalMap("lid").has_value());
  // A key with nothing under it is an empty map.
  const std::optional<YamlSection> empty = reader.Root().OptionalMap("empty");
  ASSERT_TRUE(empty.has_value());
  EXPECT_EQ(empty->Int("n", 4), 4);
  EXPECT_NO_THROW(empty->CheckNoUnknownKeys({}));
  EXPECT_NO_THROW(box.CheckNoUnknownKeys(
      {"width_m", "count", "label", "open", "corner_m", "colour", "tags", "inner"}));
}

TEST(YamlReader, LinesOfKeysAndOfTheirEnclosingMaps) {
  const YamlSection root = YamlReader(Write("yaml_lines.yaml", kGood)).Root();
  EXPECT_EQ(root.Line("box"), 2);
  EXPECT_EQ(root.Line("box.colour"), 8);
  EXPECT_EQ(root.Line("box.inner.depth_m"), 11);
  EXPECT_EQ(root.Line("box.inner.width_m"), 10) << "absent: the enclosing map's line";
  EXPECT_EQ(root.Line("box.colour.x"), 8);
  EXPECT_EQ(root.Line("empty"), 12);
  EXPECT_EQ(root.Line("missing"), 2) << "absent at the top: the first line of the map";
  EXPECT_EQ(root.Map("box").Line("open"), 6);
  EXPECT_EQ(root.Map("box").Line(""), 2);
}

TEST(YamlReader, WrongTypesNameFileLineAndField) {
  const std::string path = Write("yaml_bad.yaml",
                                 "box:\n"                      // 1
                                 "  width_m: wide\n"           // 2
                                 "  height_m: .inf\n"          // 3
                                 "  count: 2.5\n"              // 4
                                 "  open: maybe\n"             // 5
                                 "  label: [x]\n"              // 6
                                 "  corner_m: [1, 2]\n"        // 7
                                 "  origin_m: [1, x, 3]\n"     // 8
                                 "  centre_m: [1, .nan, 3]\n"  // 9
                                 "  colour: green\n"           // 10
                                 "  tags: a\n"                 // 11
                                 "  inner: 3\n"                // 12
                                 "  extra: 1\n");              // 13
  const YamlSection box = YamlReader(path).Root().Map("box");
  const std::string p = path + ":";
  EXPECT_EQ(ErrorOf([&] { box.Double("width_m", 0); }), p + "2: box.width_m: expected a number");
  EXPECT_DOUBLE_EQ(box.Double("height_m", 0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(ErrorOf([&] { box.FiniteDouble("height_m", 0); }),
            p + "3: box.height_m: expected a finite number");
  EXPECT_EQ(ErrorOf([&] { box.Int("count", 0); }), p + "4: box.count: expected an integer");
  EXPECT_EQ(ErrorOf([&] { box.Bool("open", false); }), p + "5: box.open: expected true or false");
  EXPECT_EQ(ErrorOf([&] { box.String("label", ""); }), p + "6: box.label: expected a string");
  EXPECT_EQ(ErrorOf([&] { box.Vec3("corner_m", Eigen::Vector3d::Zero()); }),
            p + "7: box.corner_m: expected [x, y, z]");
  EXPECT_EQ(ErrorOf([&] { box.Vec3("origin_m", Eigen::Vector3d::Zero()); }),
            p + "8: box.origin_m: expected three numbers");
  EXPECT_EQ(ErrorOf([&] { box.Vec3("centre_m", Eigen::Vector3d::Zero()); }),
            p + "9: box.centre_m: expected finite numbers");
  EXPECT_EQ(ErrorOf([&] { box.Enum("colour", &ParseColour, Colour::kRed); }),
            p + "10: box.colour: expected red or blue");
  EXPECT_EQ(ErrorOf([&] { box.StringList("tags"); }),
            p + "11: box.tags: expected a list of strings");
  EXPECT_EQ(ErrorOf([&] { box.Map("inner"); }), p + "12: box.inner: expected a map");
  EXPECT_EQ(ErrorOf([&] { box.OptionalMap("inner"); }), p + "12: box.inner: expected a map");
  EXPECT_EQ(ErrorOf([&] { box.Map("lid"); }), p + "1: box.lid: missing");
  EXPECT_EQ(ErrorOf([&] { box.Required("lid"); }), p + "1: box.lid: missing");
  EXPECT_EQ(ErrorOf([&] {
              box.CheckNoUnknownKeys({"width_m", "height_m", "count", "open", "label", "corner_m",
                                      "origin_m", "centre_m", "colour", "tags", "inner"});
            }),
            p + "13: box.extra: unknown key");
  EXPECT_EQ(ErrorOf([&] { box.Fail("count", "too many"); }), p + "4: box.count: too many");
  EXPECT_EQ(ErrorOf([&] { box.Fail("", "empty"); }), p + "1: box: empty");
}

TEST(YamlReader, ValidateErrorsGoToTheFieldsLine) {
  const std::string path = Write("yaml_validate.yaml", "\nbox:\n  width_m: -1\n");
  const YamlSection box = YamlReader(path).Root().Map("box");
  EXPECT_EQ(ErrorOf([&] { box.FailInvalid(std::invalid_argument("width_m: expected > 0")); }),
            path + ":3: box.width_m: expected > 0");
  // A field left at its default: the section's line.
  EXPECT_EQ(ErrorOf([&] { box.FailInvalid(std::invalid_argument("depth_m: expected > 0")); }),
            path + ":2: box.depth_m: expected > 0");
  EXPECT_EQ(ErrorOf([&] { box.FailInvalid(std::invalid_argument("inconsistent")); }),
            path + ":2: box: inconsistent");
}

TEST(YamlReader, FilesThatCannotBeReadOrParsed) {
  const std::string missing = ::testing::TempDir() + "/yaml_no_such_file.yaml";
  EXPECT_EQ(ErrorOf([&] { YamlReader{missing}; }), missing + ": cannot open file");
  try {
    YamlReader{missing};
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), missing);
    EXPECT_EQ(e.line(), 0);
    EXPECT_EQ(e.field(), "");
    EXPECT_EQ(e.reason(), "cannot open file");
  }
  const std::string malformed = Write("yaml_malformed.yaml", "a: 1\nb: [1, 2\n");
  const std::string error = ErrorOf([&] { YamlReader{malformed}; });
  EXPECT_EQ(error.rfind(malformed + ":3: malformed YAML: ", 0), 0u) << error;
  const std::string list = Write("yaml_list.yaml", "\n- 1\n- 2\n");
  EXPECT_EQ(ErrorOf([&] { YamlReader(list).Root(); }), list + ":2: expected a map at the top");
  EXPECT_EQ(ErrorOf([&] { YamlReader::FromText("", "inline").Root(); }),
            "inline:1: expected a map at the top");
  EXPECT_EQ(ErrorOf([&] { YamlReader::FromText("a: {", "inline"); }).rfind("inline:1: ", 0), 0u);
  EXPECT_EQ(YamlReader::FromText("a: 2", "inline").Root().Int("a", 0), 2);
}

}  // namespace
}  // namespace microdex
