#pragma once
// JSON text for the reports, score files and pages the project writes by hand (no JSON
// library is needed for output this simple; the readers parse with yaml-cpp or the browser).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace microdex {

// A JSON number with `digits` significant digits (printf %g); "null" for NaN and infinities
// (JSON has no such numbers). 9 digits keep a micrometre in metres; 6 suit readouts.
inline std::string JsonNumber(double v, int digits = 9) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", std::clamp(digits, 1, 17), v);
  return buf;
}

// A JSON string literal: quotes and backslashes escaped, control characters as \u00XX.
inline std::string JsonQuote(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace microdex
