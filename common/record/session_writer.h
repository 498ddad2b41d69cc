#pragma once
// Writes a session recording: one SQLite file (WAL journal) with the schema of
// instructor/README.md ("Recording"). Not thread-safe: the recorder thread owns it.

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace microdex::record {

// One recorded sample: the serialized CDR bytes of a DDS sample of one of KnownTopics().
struct RecordedMessage {
  int topic = 0;                // index into KnownTopics()
  std::string station;          // the sample's station_id (a cue command: its target)
  std::string session;          // the sample's session_id
  std::int64_t receive_ns = 0;  // CLOCK_REALTIME when the recorder took it
  std::int64_t source_ns = 0;   // the writer's source timestamp, CLOCK_REALTIME
  std::int64_t sequence = 0;    // the writer's DDS sequence number (a cue sent: its cue id)
  std::uint64_t step = 0;       // the sample's haptic step
  std::vector<std::uint8_t> cdr;
};

class SessionWriter {
 public:
  // Creates `path` (throws std::runtime_error "PATH: reason" when it exists or cannot be
  // created) with the schema, the known topics and `metadata` (added to format, schema
  // version and creation time).
  // auto_checkpoint: SQLite's own checkpoints inside commits (false: a WalCheckpointer does it).
  SessionWriter(const std::string& path, const std::map<std::string, std::string>& metadata,
                bool auto_checkpoint = false);
  ~SessionWriter();
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  // Appends the messages in one transaction (committed when this returns). Throws
  // std::runtime_error "PATH: reason" when SQLite fails (disk full, ...).
  void Write(std::span<const RecordedMessage> messages);
  // Sets (or replaces) a metadata entry, in its own transaction.
  void SetMetadata(const std::string& key, const std::string& value);

  const std::string& path() const { return path_; }

 private:
  void Exec(const char* sql);
  [[noreturn]] void Fail(const char* what) const;

  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
};

// Copies a recording's WAL into its database file from a connection of its own, so that the
// writer's commits never wait for it: SessionWriter turns SQLite's automatic checkpoint off
// (it would run inside a commit, and with synchronous=NORMAL it syncs the database file: under
// load a commit then took up to 0.66 s, the time a killed recorder could lose). A passive
// checkpoint never blocks the writer. Not thread-safe: one thread owns it.
class WalCheckpointer {
 public:
  // Opens `path` (an existing recording); throws std::runtime_error "PATH: reason".
  explicit WalCheckpointer(const std::string& path);
  ~WalCheckpointer();
  WalCheckpointer(const WalCheckpointer&) = delete;
  WalCheckpointer& operator=(const WalCheckpointer&) = delete;

  // One passive checkpoint; the WAL frames it copied, or -1 when SQLite was busy (retried by
  // the next call). Throws std::runtime_error "PATH: reason" on any other failure.
  int Checkpoint();

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

}  // namespace microdex::record
