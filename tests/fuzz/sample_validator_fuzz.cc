// libFuzzer target: the bytes as a received DDS sample of one of the topic types, deserialized
// and validated (input_exercise.h). Built with clang only (the fuzz preset):
//   build-fuzz/tests/fuzz/sample_validator_fuzz WORK tests/fuzz/corpus/sample_validator
#include <cstdint>

#include "tests/fuzz/input_exercise.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  microdex::fuzz::ExerciseSample(data, size);
  return 0;
}
