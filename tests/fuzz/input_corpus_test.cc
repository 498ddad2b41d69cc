// The scene loader, the DDS sample validators and the pages' WebSocket decoders over their
// committed seed corpora (tests/fuzz/corpus/{scene_loader,sample_validator,ws_message}) and
// over a few hundred inputs mutated from each seed (bytes flipped, cut short, bytes inserted):
// nothing crashes; the seeds named ok_* are accepted and bad_* refused; every valid sample this
// build writes deserializes and validates. The libFuzzer targets (clang, the fuzz preset)
// explore further from the same seeds; an input one of them found is kept in the corpus
// (regression_*) and replayed here. ext_* scenes name parameter files of assets/ (not found
// from a fuzz input): seeds for the fuzzer, with no expectation here.
#include <dirent.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "tests/fuzz/input_exercise.h"

namespace microdex::fuzz {
namespace {

std::string CorpusDir(const std::string& name) {
  const char* src = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(src ? src : MICRODEX_TEST_SOURCE_DIR) + "/tests/fuzz/corpus/" + name;
}

std::vector<std::string> Files(const std::string& dir) {
  std::vector<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (const dirent* e = readdir(d)) {
      if (e->d_name[0] != '.') out.push_back(e->d_name);
    }
    closedir(d);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string ReadBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// Variants of `seed`: a byte overwritten, the input cut short, random bytes inserted.
std::vector<std::string> Mutations(const std::string& seed, int count, unsigned seed_value) {
  std::mt19937 rng(seed_value);
  std::vector<std::string> out;
  for (int i = 0; i < count; ++i) {
    std::string m = seed;
    switch (rng() % 3) {
      case 0:
        for (int k = 0, n = 1 + static_cast<int>(rng() % 4); k < n && !m.empty(); ++k) {
          m[rng() % m.size()] = static_cast<char>(rng());
        }
        break;
      case 1:
        m.resize(m.empty() ? 0 : rng() % m.size());
        break;
      default: {
        const std::size_t at = m.empty() ? 0 : rng() % m.size();
        std::string noise(1 + rng() % 8, '\0');
        for (char& c : noise) c = static_cast<char>(rng());
        m.insert(at, noise);
      }
    }
    out.push_back(std::move(m));
  }
  return out;
}

TEST(InputCorpus, SceneSeedsLoadOrFailCleanly) {
  const std::string dir = CorpusDir("scene_loader");
  const auto files = Files(dir);
  ASSERT_GE(files.size(), 8u) << dir;
  int ok = 0;
  for (const auto& name : files) {
    const bool loaded = ExerciseSceneText(ReadBytes(dir + "/" + name));
    if (StartsWith(name, "ok_")) {
      EXPECT_TRUE(loaded) << name;
      ++ok;
    } else if (StartsWith(name, "bad_")) {
      EXPECT_FALSE(loaded) << name;
    }
  }
  EXPECT_GE(ok, 3);
}

TEST(InputCorpus, MutatedScenesNeverCrash) {
  const std::string dir = CorpusDir("scene_loader");
  int loaded = 0, total = 0;
  unsigned s = 1;
  for (const auto& name : Files(dir)) {
    if (!StartsWith(name, "ok_")) continue;
    for (const auto& m : Mutations(ReadBytes(dir + "/" + name), 150, s++)) {
      loaded += ExerciseSceneText(m) ? 1 : 0;
      ++total;
    }
  }
  std::printf("%d mutated scenes: %d loaded, the others refused\n", total, loaded);
  EXPECT_GT(total, 0);
}

TEST(InputCorpus, ValidSamplesOfEveryTypeDeserializeAndValidate) {
  const auto samples = ValidSamples();
  ASSERT_EQ(samples.size(), kSampleTypes);
  for (const auto& [name, bytes] : samples) {
    const SampleResult r = ExerciseSample(bytes.data(), bytes.size());
    EXPECT_TRUE(r.deserialized) << name;
    EXPECT_TRUE(r.valid) << name;
  }
}

TEST(InputCorpus, SampleSeedsAndMutationsNeverCrash) {
  const std::string dir = CorpusDir("sample_validator");
  const auto files = Files(dir);
  ASSERT_GE(files.size(), kSampleTypes) << dir;
  int deserialized = 0, valid = 0, total = 0;
  unsigned s = 100;
  for (const auto& name : files) {
    const std::string seed = ReadBytes(dir + "/" + name);
    std::vector<std::string> inputs = Mutations(seed, 300, s++);
    inputs.push_back(seed);
    for (const auto& m : inputs) {
      const SampleResult r =
          ExerciseSample(reinterpret_cast<const std::uint8_t*>(m.data()), m.size());
      deserialized += r.deserialized ? 1 : 0;
      valid += r.valid ? 1 : 0;
      ++total;
    }
  }
  std::printf("%d samples: %d deserialized, %d valid\n", total, deserialized, valid);
  EXPECT_LT(valid, total);  // the mutations are not all harmless
}

TEST(InputCorpus, WsSeedsAcceptedByExactlyOneDecoderOrRefused) {
  const std::string dir = CorpusDir("ws_message");
  const auto files = Files(dir);
  ASSERT_GE(files.size(), 10u) << dir;
  for (const auto& name : files) {
    const int accepted = ExerciseWsMessage(ReadBytes(dir + "/" + name));
    if (StartsWith(name, "ok_")) {
      EXPECT_EQ(accepted, 1) << name;
    } else if (StartsWith(name, "bad_")) {
      EXPECT_EQ(accepted, 0) << name;
    }
  }
}

TEST(InputCorpus, MutatedWsMessagesNeverCrash) {
  const std::string dir = CorpusDir("ws_message");
  int accepted = 0, total = 0;
  unsigned s = 1000;
  for (const auto& name : Files(dir)) {
    for (const auto& m : Mutations(ReadBytes(dir + "/" + name), 200, s++)) {
      accepted += ExerciseWsMessage(m) > 0 ? 1 : 0;
      ++total;
    }
  }
  std::printf("%d mutated messages: %d accepted\n", total, accepted);
  EXPECT_GT(total, 0);
}

}  // namespace
}  // namespace microdex::fuzz
