#include "common/knot/obj.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace microdex::knot {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, int line, const std::string& reason) {
  throw std::runtime_error(path.string() + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                           reason);
}

bool ParseDouble(std::string_view token, double* out) {
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), *out);
  return ec == std::errc() && ptr == token.data() + token.size();
}

bool ParseInt(std::string_view token, long* out) {
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), *out);
  return ec == std::errc() && ptr == token.data() + token.size();
}

constexpr const char* kDiameterKey = "thread_diameter_m";

struct LineElement {
  int line = 0;
  std::vector<int> indices;  // 0-based
};

}  // namespace

std::vector<Eigen::Vector3d> ReadObjPolyline(const std::filesystem::path& path,
                                             double* thread_diameter_m) {
  std::ifstream in(path);
  if (!in) Fail(path, 0, "cannot open file");
  double diameter_m = 0.0;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<LineElement> elements;
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream tokens(text);
    std::string keyword;
    if (!(tokens >> keyword)) continue;
    if (keyword == "#") {
      std::string name, token, extra;
      if (tokens >> name && name == kDiameterKey) {
        if (!(tokens >> token) || !ParseDouble(token, &diameter_m) || !std::isfinite(diameter_m) ||
            !(diameter_m > 0.0) || tokens >> extra) {
          Fail(path, line_no,
               std::string("malformed '# ") + kDiameterKey + " D', expected one positive number");
        }
      }
      continue;
    }
    if (keyword[0] == '#') continue;
    if (keyword == "v") {
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) {
        std::string token;
        if (!(tokens >> token) || !ParseDouble(token, &p[k]) || !std::isfinite(p[k])) {
          Fail(path, line_no, "malformed vertex, expected 'v x y z' with finite numbers");
        }
      }
      vertices.push_back(p);
    } else if (keyword == "l") {
      LineElement element{line_no, {}};
      std::string token;
      while (tokens >> token) {
        // "i" or "i/t": the vertex index is before the slash; negative counts from the end.
        const std::string_view index_text = std::string_view(token).substr(0, token.find('/'));
        long index = 0;
        if (!ParseInt(index_text, &index) || index == 0) {
          Fail(path, line_no, "malformed index '" + token + "' in 'l' element");
        }
        const long resolved = index > 0 ? index - 1 : static_cast<long>(vertices.size()) + index;
        if (resolved < 0 || resolved >= static_cast<long>(vertices.size())) {
          Fail(path, line_no,
               "index " + std::to_string(index) + " out of range (" +
                   std::to_string(vertices.size()) + " vertices defined so far)");
        }
        element.indices.push_back(static_cast<int>(resolved));
      }
      if (element.indices.size() < 2) Fail(path, line_no, "'l' element with fewer than 2 indices");
      elements.push_back(std::move(element));
    }
    // Other statements (vn, vt, o, g, f, ...) are not part of the polyline.
  }
  if (elements.empty()) Fail(path, 0, "no 'l' element (the thread's polyline) found");
  // Chain the elements end to end (exporters often write one element per segment).
  std::vector<int> chain = elements.front().indices;
  std::vector<bool> used(elements.size(), false);
  used[0] = true;
  for (std::size_t added = 1; added < elements.size();) {
    bool progress = false;
    for (std::size_t e = 1; e < elements.size(); ++e) {
      if (used[e]) continue;
      const auto& idx = elements[e].indices;
      if (idx.front() == chain.back()) {
        chain.insert(chain.end(), idx.begin() + 1, idx.end());
      } else if (idx.back() == chain.back()) {
        chain.insert(chain.end(), idx.rbegin() + 1, idx.rend());
      } else if (idx.back() == chain.front()) {
        chain.insert(chain.begin(), idx.begin(), idx.end() - 1);
      } else if (idx.front() == chain.front()) {
        chain.insert(chain.begin(), idx.rbegin(), idx.rend() - 1);
      } else {
        continue;
      }
      used[e] = true;
      ++added;
      progress = true;
    }
    if (!progress) {
      for (std::size_t e = 1; e < elements.size(); ++e) {
        if (!used[e]) {
          Fail(path, elements[e].line, "'l' element does not chain with the others into one path");
        }
      }
    }
  }
  std::vector<Eigen::Vector3d> nodes;
  nodes.reserve(chain.size());
  for (int i : chain) nodes.push_back(vertices[i]);
  if (thread_diameter_m != nullptr) *thread_diameter_m = diameter_m;
  return nodes;
}

void WriteObjPolyline(const std::filesystem::path& path, std::span<const Eigen::Vector3d> nodes,
                      const std::vector<std::string>& comment, double thread_diameter_m) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write file");
  for (const auto& c : comment) out << "# " << c << "\n";
  char buffer[128];
  if (thread_diameter_m > 0.0) {
    std::snprintf(buffer, sizeof(buffer), "# %s %.9g\n", kDiameterKey, thread_diameter_m);
    out << buffer;
  }
  for (const auto& p : nodes) {
    std::snprintf(buffer, sizeof(buffer), "v %.9g %.9g %.9g\n", p.x(), p.y(), p.z());
    out << buffer;
  }
  out << "l";
  for (std::size_t i = 0; i < nodes.size(); ++i) out << " " << i + 1;
  out << "\n";
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace microdex::knot
