#pragma once
// Reads a session recording (any schema version from 1 to kSchemaVersion). Every failure is a
// RecordError whose message names the file and what is wrong; damage found while reading
// messages (a truncated or corrupted file) ends the iteration and is kept in problems(), so
// the readable part can still be used.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

struct sqlite3;

namespace microdex::record {

class RecordError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SessionTopic {
  int id = 0;
  std::string name;
  std::string type;
  std::string idl_hash;
  // -1 when the topic is not one this build knows, or its IDL hash differs from this build's
  // (its bytes cannot be decoded safely): such a topic's messages are skipped.
  int known = -1;  // index into KnownTopics()
};

struct MessageView {
  int topic = 0;  // index into KnownTopics()
  std::string_view station;
  std::string_view session;
  std::int64_t receive_ns = 0;
  std::int64_t source_ns = 0;
  std::int64_t sequence = 0;
  std::uint64_t step = 0;
  std::span<const std::uint8_t> cdr;
};

struct MessageFilter {
  int topic = -1;                              // index into KnownTopics(); -1: every topic
  std::string station;                         // "": every station
  std::optional<std::int64_t> from_ns, to_ns;  // receive time range (inclusive)
};

class SessionReader {
 public:
  // Opens read-only and checks the file: an SQLite database, a microdex recording, a schema
  // version this build reads, topics whose types it knows (unknown ones are listed in
  // problems()). Throws RecordError.
  explicit SessionReader(const std::string& path);
  ~SessionReader();
  SessionReader(const SessionReader&) = delete;
  SessionReader& operator=(const SessionReader&) = delete;

  const std::string& path() const { return path_; }
  int schema_version() const { return schema_version_; }
  const std::map<std::string, std::string>& metadata() const { return metadata_; }
  const std::vector<SessionTopic>& topics() const { return topics_; }
  // What was found wrong so far, one line each ("PATH: ..."); empty for a sound file.
  const std::vector<std::string>& problems() const { return problems_; }

  // Calls `visit` for each message of a known topic matching `filter`, in the order they were
  // recorded (receive order), until it returns false. Returns how many were visited. Damage
  // met on the way ends the iteration and adds a problem.
  std::size_t ForEach(const MessageFilter& filter,
                      const std::function<bool(const MessageView&)>& visit);
  // The stations that sent anything, sorted.
  std::vector<std::string> Stations();
  // First and last receive time (0, 0 for an empty recording).
  std::pair<std::int64_t, std::int64_t> TimeRange();

 private:
  void AddProblem(const std::string& what);

  std::string path_;
  sqlite3* db_ = nullptr;
  int schema_version_ = 0;
  std::map<std::string, std::string> metadata_;
  std::vector<SessionTopic> topics_;
  std::map<int, int> topic_by_id_;  // topics.id → index into KnownTopics() (known ones only)
  std::vector<std::string> problems_;
};

}  // namespace microdex::record
