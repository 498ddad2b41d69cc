// libFuzzer target: the bytes as a WebSocket text message of a page, to every decoder
// (input_exercise.h). Built with clang only (the fuzz preset):
//   build-fuzz/tests/fuzz/ws_message_fuzz WORK tests/fuzz/corpus/ws_message
#include <cstdint>
#include <string>

#include "tests/fuzz/input_exercise.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  microdex::fuzz::ExerciseWsMessage(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
