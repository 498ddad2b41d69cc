#pragma once
// Bad input in a file (a scene, a parameter file): one exception type whose what() is the one
// line the apps print,
//
//     FILE:LINE: field: reason
//
// LINE is 1-based; it is left out (`FILE: reason`) when there is no line, e.g. for a file that
// cannot be opened, and the field is left out when the error is not about one field (a file that
// does not parse).

#include <stdexcept>
#include <string>
#include <utility>

namespace microdex {

class InputError : public std::runtime_error {
 public:
  // line <= 0: no line; an empty field: no field.
  InputError(std::string file, int line, std::string field, std::string reason)
      : std::runtime_error(Format(file, line, field, reason)),
        file_(std::move(file)),
        line_(line),
        field_(std::move(field)),
        reason_(std::move(reason)) {}

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& field() const { return field_; }
  const std::string& reason() const { return reason_; }

 private:
  static std::string Format(const std::string& file, int line, const std::string& field,
                            const std::string& reason) {
    std::string s = file;
    if (line > 0) s.append(":").append(std::to_string(line));
    s.append(": ");
    if (!field.empty()) s.append(field).append(": ");
    return s.append(reason);
  }

  std::string file_;
  int line_;
  std::string field_;
  std::string reason_;
};

}  // namespace microdex
