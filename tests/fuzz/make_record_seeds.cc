// Writes the seed corpus of the recording reader (tests/fuzz/corpus/record_reader):
//   make_record_seeds DIR
// valid.db (a small recording with every topic), and damaged variants of it.
#include <sqlite3.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/fuzz/record_reader_exercise.h"

namespace {

bool Exec(const std::string& file, const char* sql) {
  sqlite3* db = nullptr;
  bool ok = sqlite3_open(file.c_str(), &db) == SQLITE_OK &&
            sqlite3_exec(db, sql, nullptr, nullptr, nullptr) == SQLITE_OK;
  sqlite3_close(db);
  return ok;
}

std::string Copy(const std::string& from, const std::string& to) {
  std::ifstream in(from, std::ios::binary);
  std::ofstream(to, std::ios::binary | std::ios::trunc) << in.rdbuf();
  return to;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_record_seeds DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  const std::string valid = dir + "/valid.db";
  std::remove(valid.c_str());
  microdex::fuzz::WriteSeedRecording(valid);
  // Rollback journal: reading the seeds then leaves no -wal/-shm files beside them.
  Exec(valid, "PRAGMA journal_mode=DELETE");
  Exec(valid, "VACUUM");
  std::ofstream(dir + "/empty.db", std::ios::trunc).flush();
  std::ofstream(dir + "/text.db", std::ios::trunc)
      << "station,session,step\nseed-1,seed-1-1,0\nnot a database at all\n";
  {
    std::ifstream in(valid, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir + "/truncated.db", std::ios::binary | std::ios::trunc)
        << bytes.substr(0, bytes.size() * 2 / 3);
  }
  bool ok = Exec(Copy(valid, dir + "/future.db"),
                 "UPDATE metadata SET value = '999' WHERE key = 'schema_version'");
  ok = ok && Exec(Copy(valid, dir + "/unknown_hash.db"),
                  "UPDATE topics SET idl_hash = 'ffffffffffffffff' WHERE name = 'microdex/score'");
  ok = ok && Exec(Copy(valid, dir + "/bad_cdr.db"),
                  "UPDATE messages SET data = X'000100004142' WHERE topic_id = 1 AND step = 1");
  return ok ? 0 : 1;
}
