#pragma once
// Reading optional fields of a scene or parameter file (yaml-cpp; include only from targets
// that link it). A present field of the wrong type throws, naming file, field and line.

#include <yaml-cpp/yaml.h>

#include <stdexcept>
#include <string>
#include <type_traits>

namespace microdex {

// Reads root[field] into out when present; `section` prefixes the field in the message
// (e.g. "tissue."). A missing field leaves out at its default.
template <typename T>
void ReadYamlField(const YAML::Node& root, const std::string& path, const char* section,
                   const char* field, T& out) {
  const YAML::Node node = root[field];
  if (!node) return;
  try {
    out = node.as<T>();
  } catch (const YAML::Exception&) {
    throw std::runtime_error(path + ": field '" + section + field + "' (line " +
                             std::to_string(node.Mark().line + 1) + "): expected " +
                             (std::is_same_v<T, std::string> ? "a string"
                              : std::is_integral_v<T>        ? "an integer"
                                                             : "a number"));
  }
}

}  // namespace microdex
