// Writes the sample validator's seed corpus: one valid sample of every topic type
// (tests/fuzz/corpus/sample_validator/TYPE.bin). Run by hand after an IDL change; the output is
// committed:  build/tests/make_input_seeds tests/fuzz/corpus/sample_validator
#include <cstdio>
#include <fstream>

#include "tests/fuzz/input_exercise.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_input_seeds DIR\n");
    return 2;
  }
  for (const auto& [name, bytes] : microdex::fuzz::ValidSamples()) {
    const std::string path = std::string(argv[1]) + "/" + name + ".bin";
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    std::printf("%s: %zu bytes\n", path.c_str(), bytes.size());
  }
  return 0;
}
