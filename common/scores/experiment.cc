#include "common/scores/experiment.h"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/base/input_error.h"
#include "common/base/yaml_reader.h"

namespace microdex::scores {
namespace {

constexpr std::size_t kMaxName = 64;  // ids on the wire (net::kMaxIdLength)

std::uint64_t SplitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// The conditions map, read with yaml-cpp directly (YamlSection reads named fields, not a map
// of names): each key a condition, each value a list of cue specs.
std::vector<CueCondition> ReadConditions(const YAML::Node& root, const YamlSection& top) {
  const YAML::Node node = root["conditions"];
  if (!node) top.Fail("conditions", "missing");
  if (!node.IsMap()) top.Fail("conditions", "expected a map of condition name: [cue specs]");
  std::vector<CueCondition> out;
  std::set<std::string> seen;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const YAML::Node key = it->first;
    const YAML::Node cues = it->second;
    const int line = key.Mark().line + 1;
    const std::string name = key.as<std::string>();
    const std::string field = "conditions." + name;
    if (!seen.insert(name).second) throw InputError(top.file(), line, field, "defined twice");
    CueCondition c;
    c.name = name;
    if (cues.IsNull()) {
      out.push_back(std::move(c));  // `none:` with nothing: no cue
      continue;
    }
    if (!cues.IsSequence()) {
      throw InputError(top.file(), line, field,
                       "expected a list of cue specs KIND[:PARAM|:off] ([] for none)");
    }
    for (const YAML::Node& spec : cues) {
      const int spec_line = spec.Mark().line + 1;
      if (!spec.IsScalar()) {
        throw InputError(top.file(), spec_line, field, "expected a cue spec KIND[:PARAM|:off]");
      }
      const std::string text = spec.as<std::string>();
      try {
        c.cues.push_back(cues::ParseCueArg(text));
      } catch (const std::invalid_argument& e) {
        throw InputError(top.file(), spec_line, field, e.what());
      }
      c.cue_specs.push_back(text);
    }
    // The condition goes to a station as one command a cue (CueCommand.condition_size), and the
    // cue topic keeps 16 per station for a station that joins late.
    if (c.cues.size() > 16) {
      throw InputError(top.file(), line, field, "at most 16 cues in a condition");
    }
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

void ExperimentDef::Validate() const {
  const auto check_name = [](const std::string& field, const std::string& v) {
    if (v.empty() || v.size() > kMaxName || v == "null") {
      throw std::invalid_argument(field + ": expected a name of 1 to 64 characters");
    }
  };
  check_name("name", name);
  if (scene.empty() || scene == "null") throw std::invalid_argument("scene: missing");
  if (trials_per_trainee < 1 || trials_per_trainee > 1000) {
    throw std::invalid_argument("trials_per_trainee: expected 1 to 1000");
  }
  if (conditions.size() < 2) {
    throw std::invalid_argument("conditions: expected at least two conditions to compare");
  }
  for (const CueCondition& c : conditions) check_name("conditions." + c.name, c.name);
  if (trainees.size() < conditions.size()) {
    throw std::invalid_argument("trainees: expected at least one trainee per condition (" +
                                std::to_string(conditions.size()) + ")");
  }
  std::set<std::string> seen;
  for (const std::string& t : trainees) {
    check_name("trainees", t);
    if (!seen.insert(t).second) throw std::invalid_argument("trainees: '" + t + "' listed twice");
  }
}

ExperimentDef ParseExperiment(const std::string& text, const std::string& origin) {
  const YamlReader reader = YamlReader::FromText(text, origin);
  const YamlSection top = reader.Root();
  top.CheckNoUnknownKeys({"name", "scene", "seed", "trials_per_trainee", "conditions", "trainees"});
  for (const char* key : {"name", "scene", "trials_per_trainee", "conditions", "trainees"}) {
    top.Required(key);
  }
  ExperimentDef e;
  e.file = origin;
  e.name = top.String("name", "");
  e.scene = top.String("scene", "");
  const int seed = top.Int("seed", 1);
  if (seed < 0) top.Fail("seed", "expected an integer >= 0");
  e.seed = static_cast<std::uint64_t>(seed);
  e.trials_per_trainee = top.Int("trials_per_trainee", 1);
  e.trainees = top.StringList("trainees");
  const YAML::Node root = YAML::Load(text);
  e.conditions = ReadConditions(root, top);
  try {
    e.Validate();
  } catch (const std::invalid_argument& err) {
    const std::string what = err.what();
    // "conditions.NAME: ..." names a key below `conditions`, found by its line.
    const std::size_t colon = what.find(": ");
    const std::string field = what.substr(0, colon);
    if (field.rfind("conditions.", 0) == 0) {
      const YAML::Node c = root["conditions"];
      int line = top.Line("conditions");
      for (auto it = c.begin(); it != c.end(); ++it) {
        const YAML::Node key = it->first;
        if ("conditions." + key.as<std::string>() == field) line = key.Mark().line + 1;
      }
      throw InputError(origin, line, field, what.substr(colon + 2));
    }
    top.FailInvalid(err);
  }
  return e;
}

ExperimentDef ReadExperiment(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path, 0, "", "cannot open file");
  std::stringstream ss;
  ss << f.rdbuf();
  return ParseExperiment(ss.str(), path);
}

std::map<std::string, std::string> AssignConditions(const ExperimentDef& e) {
  std::vector<std::string> order = e.trainees;
  std::uint64_t state = e.seed;
  for (std::size_t i = order.size(); i > 1; --i) {
    // Lemire's unbiased bounded draw would be exact; the modulo bias of a 64-bit draw over at
    // most a few hundred trainees is below 1e-16.
    const std::size_t j = static_cast<std::size_t>(SplitMix64(state) % i);
    std::swap(order[i - 1], order[j]);
  }
  std::map<std::string, std::string> out;
  for (std::size_t i = 0; i < order.size(); ++i) {
    out[order[i]] = e.conditions[i % e.conditions.size()].name;
  }
  return out;
}

}  // namespace microdex::scores
