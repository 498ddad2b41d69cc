#include "common/base/yaml_reader.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace microdex {
namespace {

// 1-based line of a node, or `fallback` when yaml-cpp has no mark for it.
int LineOf(const YAML::Node& node, int fallback) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? fallback : mark.line + 1;
}

// The key node of `key` in a map; an undefined node when absent.
YAML::Node KeyNode(const YAML::Node& map, std::string_view key) {
  for (const auto& entry : map) {
    if (entry.first.IsScalar() && entry.first.Scalar() == key) return entry.first;
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

}  // namespace

YamlSection::YamlSection(std::string file, const YAML::Node& node, std::string prefix, int line)
    : file_(std::move(file)), node_(node), prefix_(std::move(prefix)), line_(line) {}

std::string YamlSection::Field(std::string_view key) const { return prefix_ + std::string(key); }

bool YamlSection::Has(const char* key) const { return Value(key).IsDefined(); }

YAML::Node YamlSection::Value(const char* key) const {
  const YAML::Node& map = node_;
  return map[key];
}

double YamlSection::Double(const char* key, double fallback) const {
  const YAML::Node n = Value(key);
  if (!n) return fallback;
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected a number");
  }
}

double YamlSection::FiniteDouble(const char* key, double fallback) const {
  if (!Has(key)) return fallback;
  const double v = Double(key, fallback);
  if (!std::isfinite(v)) Fail(key, "expected a finite number");
  return v;
}

int YamlSection::Int(const char* key, int fallback) const {
  const YAML::Node n = Value(key);
  if (!n) return fallback;
  try {
    return n.as<int>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected an integer");
  }
}

bool YamlSection::Bool(const char* key, bool fallback) const {
  const YAML::Node n = Value(key);
  if (!n) return fallback;
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected true or false");
  }
}

std::string YamlSection::String(const char* key, const std::string& fallback) const {
  const YAML::Node n = Value(key);
  if (!n) return fallback;
  try {
    return n.as<std::string>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected a string");
  }
}

Eigen::Vector3d YamlSection::Vec3(const char* key, const Eigen::Vector3d& fallback) const {
  const YAML::Node n = Value(key);
  if (!n) return fallback;
  if (!n.IsSequence() || n.size() != 3) Fail(key, "expected [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    try {
      v[i] = n[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, "expected three numbers");
    }
    if (!std::isfinite(v[i])) Fail(key, "expected finite numbers");
  }
  return v;
}

std::vector<std::string> YamlSection::StringList(const char* key) const {
  const YAML::Node n = Value(key);
  if (!n) return {};
  if (!n.IsSequence()) Fail(key, "expected a list of strings");
  std::vector<std::string> out;
  for (const auto& item : n) {
    if (!item.IsScalar()) Fail(key, "expected a list of strings");
    out.push_back(item.Scalar());
  }
  return out;
}

YamlSection YamlSection::Map(const char* key) const {
  Required(key);
  const YAML::Node n = Value(key);
  if (!n.IsMap()) Fail(key, "expected a map");
  return YamlSection(file_, n, Field(key) + ".", Line(key));
}

std::optional<YamlSection> YamlSection::OptionalMap(const char* key) const {
  const YAML::Node n = Value(key);
  if (!n) return std::nullopt;
  if (n.IsNull()) {
    return YamlSection(file_, YAML::Node(YAML::NodeType::Map), Field(key) + ".", Line(key));
  }
  if (!n.IsMap()) Fail(key, "expected a map");
  return YamlSection(file_, n, Field(key) + ".", Line(key));
}

void YamlSection::Required(const char* key) const {
  if (!Has(key)) throw InputError(file_, line_, Field(key), "missing");
}

void YamlSection::CheckNoUnknownKeys(std::initializer_list<std::string_view> known) const {
  CheckNoUnknownKeys(std::span<const std::string_view>(known.begin(), known.size()));
}

void YamlSection::CheckNoUnknownKeys(std::span<const std::string_view> known) const {
  for (const auto& entry : node_) {
    std::string key = "?";
    try {
      key = entry.first.as<std::string>();
    } catch (const YAML::Exception&) {
    }
    bool found = false;
    for (std::string_view k : known) found = found || key == k;
    if (!found) throw InputError(file_, LineOf(entry.first, line_), Field(key), "unknown key");
  }
}

int YamlSection::Line(std::string_view path) const {
  if (path.empty()) return line_;
  const std::size_t dot = path.find('.');
  const std::string key(path.substr(0, dot));
  const YAML::Node key_node = KeyNode(node_, key);
  if (!key_node.IsDefined()) return line_;
  const int line = LineOf(key_node, line_);
  if (dot == std::string_view::npos) return line;
  const YAML::Node value = Value(key.c_str());
  if (!value.IsMap()) return line;
  return YamlSection(file_, value, "", line).Line(path.substr(dot + 1));
}

void YamlSection::Fail(std::string_view path, const std::string& reason) const {
  std::string field = Field(path);
  if (path.empty() && !field.empty()) field.pop_back();  // the section itself: no trailing dot
  throw InputError(file_, Line(path), field, reason);
}

void YamlSection::FailInvalid(const std::invalid_argument& e) const {
  const std::string message = e.what();
  const std::size_t colon = message.find(": ");
  if (colon == std::string::npos) Fail("", message);
  Fail(std::string_view(message).substr(0, colon), message.substr(colon + 2));
}

YamlReader::YamlReader(const std::string& path) : file_(path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  root_ = Parse(text.str(), path);
}

YamlReader YamlReader::FromText(const std::string& text, const std::string& origin) {
  return YamlReader(origin, Parse(text, origin));
}

YAML::Node YamlReader::Parse(const std::string& text, const std::string& origin) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(origin, e.mark.is_null() ? 1 : e.mark.line + 1, "",
                     "malformed YAML: " + e.msg);
  }
}

YamlSection YamlReader::Root() const {
  if (!root_.IsMap()) throw InputError(file_, LineOf(root_, 1), "", "expected a map at the top");
  return YamlSection(file_, root_, "", LineOf(root_, 1));
}

}  // namespace microdex
