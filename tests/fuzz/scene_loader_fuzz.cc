// libFuzzer target: the bytes as a scene file (input_exercise.h). Built with clang only
// (the fuzz preset):
//   build-fuzz/tests/fuzz/scene_loader_fuzz -max_total_time=60 WORK tests/fuzz/corpus/scene_loader
#include <cstdint>
#include <string_view>

#include "tests/fuzz/input_exercise.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  microdex::fuzz::ExerciseSceneText(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
