// The recording reader over the committed seed corpus (tests/fuzz/corpus/record_reader) and
// over a few hundred files mutated from the valid seed (bytes flipped, cut short, a page
// overwritten): it never crashes, an error names the file, and the valid seed reads and
// decodes every message. The libFuzzer target (record_reader_fuzz.cc, clang builds) explores
// further from the same seeds.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <iterator>

#include "tests/fuzz/record_reader_exercise.h"

namespace microdex::fuzz {
namespace {

std::string CorpusDir() {
  const char* src = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(src ? src : MICRODEX_TEST_SOURCE_DIR) + "/tests/fuzz/corpus/record_reader";
}

std::string ReadBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// An error, if any, names the file first; so does every problem.
void ExpectNamed(const std::string& path, const ExerciseResult& r) {
  if (!r.opened) {
    EXPECT_EQ(r.error.rfind(path + ": ", 0), 0u) << r.error;
  }
  if (r.problems > 0) {
    EXPECT_EQ(r.first_problem.rfind(path + ": ", 0), 0u) << r.first_problem;
  }
}

std::string TmpDir() {
  std::string dir = "/tmp/microdex-record-corpus-XXXXXX";
  return mkdtemp(dir.data()) ? dir : "/tmp";
}

// The valid seed as this build writes it (the committed one carries the IDL hashes of the
// build that wrote it; after an IDL change its topics read as unknown until regenerated).
std::string FreshValidSeed(const std::string& dir) {
  std::string path = dir + "/valid.db";
  std::remove(path.c_str());
  WriteSeedRecording(path);
  return path;
}

TEST(RecordReaderCorpus, TheValidSeedReadsAndDecodesEveryMessage) {
  const std::string path = FreshValidSeed(TmpDir());
  const ExerciseResult r = ExerciseReader(path);
  ASSERT_TRUE(r.opened) << r.error;
  EXPECT_EQ(r.messages, 14u);  // WriteSeedRecording: one or more of every topic
  EXPECT_EQ(r.decoded, r.messages);
  EXPECT_EQ(r.problems, 0u) << r.first_problem;
}

TEST(RecordReaderCorpus, EverySeedFailsCleanlyOrReads) {
  for (const char* name : {"valid.db", "empty.db", "text.db", "truncated.db", "future.db",
                           "unknown_hash.db", "bad_cdr.db", "regression_leak_on_fail.db"}) {
    const std::string path = CorpusDir() + "/" + name;
    ASSERT_FALSE(ReadBytes(path).empty() && std::string(name) != "empty.db") << path;
    const ExerciseResult r = ExerciseReader(path);
    ExpectNamed(path, r);
    if (std::string(name) == "future.db") {
      EXPECT_NE(r.error.find("schema version 999 is newer"), std::string::npos) << r.error;
    }
    if (std::string(name) == "unknown_hash.db") {
      EXPECT_NE(r.first_problem.find("unknown type hash"), std::string::npos) << r.first_problem;
    }
    if (std::string(name) == "bad_cdr.db") {
      EXPECT_TRUE(r.opened);
      EXPECT_LT(r.decoded, r.messages);
    }
  }
}

TEST(RecordReaderCorpus, MutatedFilesNeverCrashTheReader) {
  const std::string dir = TmpDir();
  const std::string seed = ReadBytes(FreshValidSeed(dir));
  ASSERT_GT(seed.size(), 4096u);
  const std::string path = dir + "/mutated.db";
  std::uint64_t x = 0x9e3779b97f4a7c15ULL;  // xorshift64: the same mutations on every run
  const auto next = [&x] {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return x;
  };
  std::size_t opened = 0, failed = 0;
  for (int i = 0; i < 300; ++i) {
    std::string bytes = seed;
    switch (i % 3) {
      case 0:  // a few bytes flipped
        for (std::uint64_t k = 0, n = 1 + next() % 16; k < n; ++k) {
          bytes[next() % bytes.size()] ^= static_cast<char>(1 + next() % 255);
        }
        break;
      case 1:  // cut short
        bytes.resize(next() % bytes.size());
        break;
      case 2: {  // one 4 KiB page overwritten with noise
        const std::size_t page = (next() % (bytes.size() / 4096)) * 4096;
        for (std::size_t k = page; k < page + 4096 && k < bytes.size(); ++k) {
          bytes[k] = static_cast<char>(next());
        }
        break;
      }
    }
    WriteBytes(path, bytes);
    const ExerciseResult r = ExerciseReader(path);
    ExpectNamed(path, r);
    (r.opened ? opened : failed) += 1;
  }
  // Both outcomes occur: the mutations reach past the header into the data.
  EXPECT_GT(opened, 0u);
  EXPECT_GT(failed, 0u);
  std::remove(path.c_str());
  std::remove((dir + "/valid.db").c_str());
  rmdir(dir.c_str());
}

}  // namespace
}  // namespace microdex::fuzz
