// Knot recognition: see knot_recognition.h. (Implementation in progress: the API is stable.)
#include "common/thread/knot_recognition.h"

#include <array>
#include <stdexcept>

namespace microdex::thread {
namespace {
constexpr std::array<std::string_view, 9> kKnotNames = {
    "none",   "overhand-left", "overhand-right", "double-overhand", "figure-eight",
    "square", "granny",        "surgeons",       "unknown"};
}  // namespace

std::string_view KnotName(KnotType type) { return kKnotNames[static_cast<int>(type)]; }

std::optional<KnotType> KnotTypeFromName(std::string_view name) {
  for (std::size_t i = 0; i < kKnotNames.size(); ++i) {
    if (kKnotNames[i] == name) return static_cast<KnotType>(i);
  }
  return std::nullopt;
}

void KnotOptions::Validate() const {}

KnotAnalysis AnalyzeKnot(std::span<const Eigen::Vector3d> polyline, const KnotOptions& options) {
  options.Validate();
  if (polyline.size() < 2) throw std::invalid_argument("knot polyline: fewer than 2 nodes");
  return KnotAnalysis{};
}

KnotType RecognizeKnot(std::span<const Eigen::Vector3d> polyline, const KnotOptions& options) {
  return AnalyzeKnot(polyline, options).type;
}

void KnotTargetDef::Validate() const {}

KnotPlacement CalcKnotPlacement(const KnotAnalysis& analysis, const KnotTargetDef& target) {
  target.Validate();
  if (!analysis.located) throw std::invalid_argument("knot placement: knot not located");
  return KnotPlacement{};
}

}  // namespace microdex::thread
