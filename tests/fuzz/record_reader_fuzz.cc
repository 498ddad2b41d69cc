// libFuzzer target: the bytes as a recording file, opened, read and decoded
// (record_reader_exercise.h). Built with clang only (-fsanitize=fuzzer):
//   build-clang/tests/fuzz/record_reader_fuzz tests/fuzz/corpus/record_reader
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "tests/fuzz/record_reader_exercise.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/microdex-record-fuzz-" + std::to_string(getpid());
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  microdex::fuzz::ExerciseReader(path);
  return 0;
}
