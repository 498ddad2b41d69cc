#include "common/record/session_reader.h"

#include <sqlite3.h>
#include <sys/stat.h>

#include <algorithm>

#include "common/record/recorded_topics.h"

namespace microdex::record {
namespace {

// A prepared statement freed on every path.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) { rc_ = sqlite3_prepare_v2(db, sql, -1, &st_, nullptr); }
  ~Statement() { sqlite3_finalize(st_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  bool ok() const { return rc_ == SQLITE_OK; }
  sqlite3_stmt* get() { return st_; }

 private:
  sqlite3_stmt* st_ = nullptr;
  int rc_ = SQLITE_OK;
};

std::string Text(sqlite3_stmt* st, int col) {
  const auto* p = sqlite3_column_text(st, col);
  return p ? std::string(reinterpret_cast<const char*>(p),
                         static_cast<std::size_t>(sqlite3_column_bytes(st, col)))
           : std::string();
}

}  // namespace

SessionReader::SessionReader(const std::string& path) : path_(path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw RecordError(path + ": no such file");
  if (!S_ISREG(st.st_mode)) throw RecordError(path + ": not a regular file");
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw RecordError(path + ": cannot open: " + why);
  }
  // close_v2: fail() runs while a Statement is still alive; sqlite3_close would refuse (BUSY)
  // and leak the connection (found by tests/fuzz/record_reader_fuzz.cc).
  auto fail = [&](const std::string& what) {
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw RecordError(path + ": " + what);
  };
  {
    Statement s(db_, "SELECT key, value FROM metadata");
    if (!s.ok()) {
      const int code = sqlite3_errcode(db_);
      if (code == SQLITE_NOTADB) fail("not an SQLite database");
      if (code == SQLITE_CORRUPT) fail(std::string("damaged: ") + sqlite3_errmsg(db_));
      fail(std::string("not a microdex recording (") + sqlite3_errmsg(db_) + ")");
    }
    int rc = 0;
    while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
      metadata_[Text(s.get(), 0)] = Text(s.get(), 1);
    }
    if (rc != SQLITE_DONE) fail(std::string("metadata: ") + sqlite3_errmsg(db_));
  }
  if (metadata_["format"] != kFormatName) {
    fail("not a microdex recording (metadata format is '" + metadata_["format"] + "')");
  }
  const std::string& v = metadata_["schema_version"];
  char* end = nullptr;
  const long version = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || version < 1) fail("metadata schema_version: '" + v + "'");
  if (version > kSchemaVersion) {
    fail("schema version " + v + " is newer than this build reads (" +
         std::to_string(kSchemaVersion) + "): use a newer microdex-replay");
  }
  schema_version_ = static_cast<int>(version);
  {
    Statement s(db_, "SELECT id, name, type, idl_hash FROM topics ORDER BY id");
    if (!s.ok()) fail(std::string("topics: ") + sqlite3_errmsg(db_));
    int rc = 0;
    while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
      SessionTopic t;
      t.id = sqlite3_column_int(s.get(), 0);
      t.name = Text(s.get(), 1);
      t.type = Text(s.get(), 2);
      t.idl_hash = Text(s.get(), 3);
      const int k = FindTopic(t.name);
      if (k < 0) {
        AddProblem("topic '" + t.name + "': not known to this build (skipped)");
      } else if (KnownTopics()[static_cast<std::size_t>(k)].type != t.type) {
        AddProblem("topic '" + t.name + "': type '" + t.type + "', this build has '" +
                   KnownTopics()[static_cast<std::size_t>(k)].type + "' (skipped)");
      } else if (KnownTopics()[static_cast<std::size_t>(k)].idl_hash != t.idl_hash) {
        AddProblem("topic '" + t.name + "': unknown type hash " + t.idl_hash + " of " + t.type +
                   " (this build: " + KnownTopics()[static_cast<std::size_t>(k)].idl_hash +
                   "; recorded by another version, skipped)");
      } else {
        t.known = k;
        topic_by_id_[t.id] = k;
      }
      topics_.push_back(std::move(t));
    }
    if (rc != SQLITE_DONE) fail(std::string("topics: ") + sqlite3_errmsg(db_));
  }
  // The messages table and its columns must be there (a damaged file may still lack rows).
  Statement s(db_,
              "SELECT topic_id, station, session, receive_ns, source_ns, sequence, step, data "
              "FROM messages LIMIT 0");
  if (!s.ok()) fail(std::string("messages: ") + sqlite3_errmsg(db_));
}

SessionReader::~SessionReader() { sqlite3_close_v2(db_); }

void SessionReader::AddProblem(const std::string& what) {
  const std::string line = path_ + ": " + what;
  if (std::find(problems_.begin(), problems_.end(), line) == problems_.end()) {
    problems_.push_back(line);
  }
}

std::size_t SessionReader::ForEach(const MessageFilter& filter,
                                   const std::function<bool(const MessageView&)>& visit) {
  std::string sql =
      "SELECT topic_id, station, session, receive_ns, source_ns, sequence, step, data FROM "
      "messages WHERE 1";
  int topic_id = -1;
  if (filter.topic >= 0) {
    for (const auto& [id, k] : topic_by_id_) {
      if (k == filter.topic) topic_id = id;
    }
    if (topic_id < 0) return 0;  // not recorded, or not readable (a problem already)
    sql += " AND topic_id = ?1";
  }
  if (!filter.station.empty()) sql += " AND station = ?2";
  if (filter.from_ns) sql += " AND receive_ns >= ?3";
  if (filter.to_ns) sql += " AND receive_ns <= ?4";
  sql += " ORDER BY id";
  Statement s(db_, sql.c_str());
  if (!s.ok()) {
    AddProblem(std::string("messages: ") + sqlite3_errmsg(db_));
    return 0;
  }
  sqlite3_stmt* st = s.get();
  if (filter.topic >= 0) sqlite3_bind_int(st, 1, topic_id);
  if (!filter.station.empty()) sqlite3_bind_text(st, 2, filter.station.c_str(), -1, SQLITE_STATIC);
  if (filter.from_ns) sqlite3_bind_int64(st, 3, *filter.from_ns);
  if (filter.to_ns) sqlite3_bind_int64(st, 4, *filter.to_ns);
  std::size_t n = 0;
  int rc = 0;
  std::size_t skipped_bad_rows = 0;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    const auto it = topic_by_id_.find(sqlite3_column_int(st, 0));
    if (it == topic_by_id_.end()) continue;  // a topic this build cannot decode (a problem)
    if (sqlite3_column_type(st, 7) != SQLITE_BLOB || sqlite3_column_type(st, 1) != SQLITE_TEXT) {
      ++skipped_bad_rows;
      continue;
    }
    MessageView m;
    m.topic = it->second;
    const auto* station = sqlite3_column_text(st, 1);
    m.station = std::string_view(reinterpret_cast<const char*>(station),
                                 static_cast<std::size_t>(sqlite3_column_bytes(st, 1)));
    if (const auto* session = sqlite3_column_text(st, 2)) {
      m.session = std::string_view(reinterpret_cast<const char*>(session),
                                   static_cast<std::size_t>(sqlite3_column_bytes(st, 2)));
    }
    m.receive_ns = sqlite3_column_int64(st, 3);
    m.source_ns = sqlite3_column_int64(st, 4);
    m.sequence = sqlite3_column_int64(st, 5);
    m.step = static_cast<std::uint64_t>(sqlite3_column_int64(st, 6));
    const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(st, 7));
    m.cdr =
        std::span<const std::uint8_t>(data, static_cast<std::size_t>(sqlite3_column_bytes(st, 7)));
    ++n;
    if (!visit(m)) break;
  }
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
    AddProblem("damaged after " + std::to_string(n) + " readable messages: " + sqlite3_errmsg(db_));
  }
  if (skipped_bad_rows > 0) {
    AddProblem(std::to_string(skipped_bad_rows) + " messages with a wrong column type (skipped)");
  }
  return n;
}

std::vector<std::string> SessionReader::Stations() {
  std::vector<std::string> out;
  Statement s(db_, "SELECT DISTINCT station FROM messages ORDER BY station");
  if (!s.ok()) {
    AddProblem(std::string("messages: ") + sqlite3_errmsg(db_));
    return out;
  }
  int rc = 0;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) out.push_back(Text(s.get(), 0));
  if (rc != SQLITE_DONE) AddProblem(std::string("stations: ") + sqlite3_errmsg(db_));
  return out;
}

std::pair<std::int64_t, std::int64_t> SessionReader::TimeRange() {
  Statement s(db_, "SELECT MIN(receive_ns), MAX(receive_ns) FROM messages");
  if (!s.ok() || sqlite3_step(s.get()) != SQLITE_ROW) {
    AddProblem(std::string("time range: ") + sqlite3_errmsg(db_));
    return {0, 0};
  }
  return {sqlite3_column_int64(s.get(), 0), sqlite3_column_int64(s.get(), 1)};
}

}  // namespace microdex::record
