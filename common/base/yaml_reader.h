#pragma once
// The one reader of the project's YAML files (scenes, tissue and thread parameter files; target
// microdex_yaml). Every bad-input error is an InputError
//
//     FILE:LINE: section.field: reason
//
// with LINE the 1-based line of the offending key; for a missing field the line of the map that
// should hold it; for a file that does not parse, yaml-cpp's line. A file that cannot be opened
// gives `FILE: cannot open file` (no line).
//
//   const YamlSection tissue = YamlReader(path).Root().Map("tissue");
//   tissue.CheckNoUnknownKeys({"level", "grading"});
//   def.level = tissue.Int("level", def.level);
//   try {
//     def.Validate();  // std::invalid_argument "level: expected ..."
//   } catch (const std::invalid_argument& e) {
//     tissue.FailInvalid(e);  // InputError "FILE:LINE: tissue.level: expected ..."
//   }

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <initializer_list>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/base/input_error.h"

namespace microdex {

// A map in a YAML file: its node, the dotted prefix of its fields ("" at the top, "tissue."
// below `tissue:`) and its line. The readers of optional fields return `fallback` when the key
// is absent and throw InputError when it is present with the wrong type.
class YamlSection {
 public:
  YamlSection(std::string file, const YAML::Node& node, std::string prefix, int line);

  const std::string& file() const { return file_; }
  // The fully qualified name of a field of this section: prefix + key.
  std::string Field(std::string_view key) const;
  bool Has(const char* key) const;

  double Double(const char* key, double fallback) const;        // any number, .nan and .inf too
  double FiniteDouble(const char* key, double fallback) const;  // `fallback` itself unchecked
  int Int(const char* key, int fallback) const;
  bool Bool(const char* key, bool fallback) const;
  // A scalar's text (yaml-cpp's conversion: an empty value reads as "null").
  std::string String(const char* key, const std::string& fallback) const;
  // [x, y, z] of finite numbers.
  Eigen::Vector3d Vec3(const char* key, const Eigen::Vector3d& fallback) const;
  // A list of scalars; absent: empty.
  std::vector<std::string> StringList(const char* key) const;
  // A string turned into a value by `parse`, which throws std::invalid_argument (its message
  // becomes the reason) for text it does not accept.
  template <typename T>
  T Enum(const char* key, T (*parse)(const std::string&), const T& fallback) const {
    if (!Has(key)) return fallback;
    const std::string text = String(key, "");
    try {
      return parse(text);
    } catch (const std::invalid_argument& e) {
      Fail(key, e.what());
    }
  }

  // A required sub-map (absent: an error at this section's line).
  YamlSection Map(const char* key) const;
  // An optional sub-map: nullopt when absent; a key with no value (`key:` and nothing under it)
  // is an empty map.
  std::optional<YamlSection> OptionalMap(const char* key) const;
  // Throws "FIELD: missing" at this section's line when the key is absent.
  void Required(const char* key) const;
  // Throws "FIELD: unknown key" for the first key not in `known`.
  void CheckNoUnknownKeys(std::initializer_list<std::string_view> known) const;
  void CheckNoUnknownKeys(std::span<const std::string_view> known) const;

  // The line of a field given by its dotted path below this section ("level",
  // "vessel.tube_radius_m"): its key's line, or the line of the nearest enclosing map present
  // in the file.
  int Line(std::string_view path) const;
  // Throws InputError at Line(path) for the field prefix + path ("" names the section itself).
  [[noreturn]] void Fail(std::string_view path, const std::string& reason) const;
  // Rethrows a Validate() error, std::invalid_argument "path: reason" (path below this
  // section), as Fail(path, reason).
  [[noreturn]] void FailInvalid(const std::invalid_argument& e) const;

 private:
  YAML::Node Value(const char* key) const;  // undefined when absent

  std::string file_;
  YAML::Node node_;  // a map
  std::string prefix_;
  int line_;
};

// A parsed YAML file (or text).
class YamlReader {
 public:
  // Opens and parses the file; throws InputError.
  explicit YamlReader(const std::string& path);
  // Parses text; `origin` stands for the file in messages. Throws InputError.
  static YamlReader FromText(const std::string& text, const std::string& origin);

  const std::string& file() const { return file_; }
  // The top level, which must be a map.
  YamlSection Root() const;

 private:
  YamlReader(std::string file, const YAML::Node& root) : file_(std::move(file)), root_(root) {}
  static YAML::Node Parse(const std::string& text, const std::string& origin);

  std::string file_;
  YAML::Node root_;
};

}  // namespace microdex
