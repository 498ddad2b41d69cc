#pragma once
// What the reader fuzz target and the corpus test do with one file: open it as a recording,
// read every message and decode each with its type. Must never crash, whatever the bytes.

#include <string>

namespace microdex::fuzz {

struct ExerciseResult {
  bool opened = false;
  std::string error;         // the RecordError's message when it did not open
  std::size_t messages = 0;  // read
  std::size_t decoded = 0;   // of those, decoded by their type
  std::size_t problems = 0;  // reader.problems() after reading
  std::string first_problem;
};

ExerciseResult ExerciseReader(const std::string& path);

// Writes a small recording with one or more real samples of every topic (the seed corpus).
void WriteSeedRecording(const std::string& path);

}  // namespace microdex::fuzz
