#include "common/record/session_writer.h"

#include <sqlite3.h>
#include <sys/stat.h>
#include <time.h>

#include <stdexcept>

#include "common/record/recorded_topics.h"

namespace microdex::record {
namespace {

// Schema version 1 (instructor/README.md documents every column).
constexpr const char* kSchemaSql = R"sql(
CREATE TABLE metadata (
  key   TEXT PRIMARY KEY,
  value TEXT NOT NULL
);
CREATE TABLE topics (
  id                   INTEGER PRIMARY KEY,
  name                 TEXT NOT NULL UNIQUE,
  type                 TEXT NOT NULL,
  serialization_format TEXT NOT NULL,
  idl_file             TEXT NOT NULL,
  idl_hash             TEXT NOT NULL
);
CREATE TABLE messages (
  id         INTEGER PRIMARY KEY,
  topic_id   INTEGER NOT NULL REFERENCES topics(id),
  station    TEXT NOT NULL,
  session    TEXT NOT NULL,
  receive_ns INTEGER NOT NULL,
  source_ns  INTEGER NOT NULL,
  sequence   INTEGER NOT NULL,
  step       INTEGER NOT NULL,
  data       BLOB NOT NULL
);
CREATE INDEX messages_by_time ON messages(receive_ns);
CREATE INDEX messages_by_station ON messages(station, topic_id);
)sql";

std::int64_t RealtimeNowNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

SessionWriter::SessionWriter(const std::string& path,
                             const std::map<std::string, std::string>& metadata,
                             bool auto_checkpoint)
    : path_(path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    throw std::runtime_error(path + ": already exists (a recording is never overwritten)");
  }
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(path + ": cannot create: " + why);
  }
  // WAL: a reader may open the file while it is written, and a killed recorder leaves every
  // committed transaction readable. synchronous=NORMAL: a commit survives the process being
  // killed (it is in the OS's buffers); only a power cut may lose the last ones.
  // The WAL is checkpointed by a WalCheckpointer on its own connection, not inside a commit.
  Exec("PRAGMA journal_mode=WAL");
  Exec("PRAGMA synchronous=NORMAL");
  if (!auto_checkpoint) Exec("PRAGMA wal_autocheckpoint=0");
  Exec("BEGIN");
  Exec(kSchemaSql);
  {
    sqlite3_stmt* st_topic = nullptr;
    if (sqlite3_prepare_v2(db_,
                           "INSERT INTO topics(id, name, type, serialization_format, idl_file, "
                           "idl_hash) VALUES (?, ?, ?, 'cdr', ?, ?)",
                           -1, &st_topic, nullptr) != SQLITE_OK) {
      Fail("prepare topics");
    }
    const auto& topics = KnownTopics();
    for (std::size_t i = 0; i < topics.size(); ++i) {
      sqlite3_bind_int(st_topic, 1, static_cast<int>(i));
      sqlite3_bind_text(st_topic, 2, topics[i].name.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(st_topic, 3, topics[i].type.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(st_topic, 4, topics[i].idl_file.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(st_topic, 5, topics[i].idl_hash.c_str(), -1, SQLITE_TRANSIENT);
      if (sqlite3_step(st_topic) != SQLITE_DONE) {
        sqlite3_finalize(st_topic);
        Fail("insert topics");
      }
      sqlite3_reset(st_topic);
    }
    sqlite3_finalize(st_topic);
  }
  std::map<std::string, std::string> meta = metadata;
  meta["format"] = kFormatName;
  meta["schema_version"] = std::to_string(kSchemaVersion);
  meta["created_ns"] = std::to_string(RealtimeNowNs());
  Exec("COMMIT");
  for (const auto& [k, v] : meta) SetMetadata(k, v);
  if (sqlite3_prepare_v2(db_,
                         "INSERT INTO messages(topic_id, station, session, receive_ns, source_ns, "
                         "sequence, step, data) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                         -1, &insert_, nullptr) != SQLITE_OK) {
    Fail("prepare messages");
  }
}

SessionWriter::~SessionWriter() {
  sqlite3_finalize(insert_);
  sqlite3_close(db_);  // checkpoints the WAL into the file
}

void SessionWriter::Fail(const char* what) const {
  throw std::runtime_error(path_ + ": " + what + ": " + sqlite3_errmsg(db_));
}

void SessionWriter::Exec(const char* sql) {
  if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK) Fail("SQL");
}

void SessionWriter::SetMetadata(const std::string& key, const std::string& value) {
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(db_, "INSERT OR REPLACE INTO metadata(key, value) VALUES (?, ?)", -1, &st,
                         nullptr) != SQLITE_OK) {
    Fail("prepare metadata");
  }
  sqlite3_bind_text(st, 1, key.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(st, 2, value.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE) Fail("insert metadata");
}

void SessionWriter::Write(std::span<const RecordedMessage> messages) {
  if (messages.empty()) return;
  Exec("BEGIN");
  for (const RecordedMessage& m : messages) {
    sqlite3_bind_int(insert_, 1, m.topic);
    sqlite3_bind_text(insert_, 2, m.station.data(), static_cast<int>(m.station.size()),
                      SQLITE_STATIC);
    sqlite3_bind_text(insert_, 3, m.session.data(), static_cast<int>(m.session.size()),
                      SQLITE_STATIC);
    sqlite3_bind_int64(insert_, 4, m.receive_ns);
    sqlite3_bind_int64(insert_, 5, m.source_ns);
    sqlite3_bind_int64(insert_, 6, m.sequence);
    sqlite3_bind_int64(insert_, 7, static_cast<sqlite3_int64>(m.step));
    sqlite3_bind_blob(insert_, 8, m.cdr.data(), static_cast<int>(m.cdr.size()), SQLITE_STATIC);
    const int rc = sqlite3_step(insert_);
    sqlite3_reset(insert_);
    if (rc != SQLITE_DONE) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      Fail("insert");
    }
  }
  Exec("COMMIT");
}

WalCheckpointer::WalCheckpointer(const std::string& path) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(path + ": cannot open for checkpoints: " + why);
  }
  sqlite3_busy_timeout(db_, 0);
  // A connection learns that the file is in WAL mode when it first reads it; until then a
  // checkpoint does nothing.
  if (sqlite3_exec(db_, "SELECT count(*) FROM sqlite_master", nullptr, nullptr, nullptr) !=
      SQLITE_OK) {
    const std::string why = sqlite3_errmsg(db_);
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(path + ": cannot read for checkpoints: " + why);
  }
}

WalCheckpointer::~WalCheckpointer() { sqlite3_close(db_); }

int WalCheckpointer::Checkpoint() {
  int log_frames = 0;
  int copied = 0;
  const int rc =
      sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_PASSIVE, &log_frames, &copied);
  if (rc == SQLITE_BUSY || rc == SQLITE_LOCKED) return -1;
  if (rc != SQLITE_OK) {
    throw std::runtime_error(path_ + ": checkpoint: " + sqlite3_errmsg(db_));
  }
  return copied;
}

}  // namespace microdex::record
