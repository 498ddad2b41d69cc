#pragma once
// The scores database: trainees, courses, sessions, scenes, scores and events across sessions
// (and the cue experiments run on them). SQLite by default (one file per course), PostgreSQL
// for a department (`postgresql://...`). The same schema and migrations on both: each
// migration is one SQL text in the subset both dialects accept, applied in its own
// transaction and recorded in `schema_version`; a database written by a newer build (a
// version this build does not know) is refused. The schema: instructor/README.md
// ("Scores database").
//
// Not thread-safe: one thread owns a ScoresDb.

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace microdex::scores {

// The schema version this build writes and reads (the last of Migrations()).
inline constexpr int kScoresSchemaVersion = 2;

class ScoresDbError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A bound parameter or a result cell: NULL, integer, real or text.
using SqlValue = std::variant<std::monostate, std::int64_t, double, std::string>;

struct SqlRow {
  std::vector<std::optional<std::string>> cells;  // as text; nullopt: NULL
  std::string Text(std::size_t i) const;          // "" for NULL
  std::int64_t Int(std::size_t i) const;          // 0 for NULL
  double Real(std::size_t i) const;               // NaN for NULL
  bool IsNull(std::size_t i) const { return !cells.at(i).has_value(); }
};

// One step of the schema: its version and its SQL (statements separated by ';'). The token
// {{serial}} stands for an auto-numbered integer primary key (SQLite: INTEGER PRIMARY KEY
// AUTOINCREMENT; PostgreSQL: BIGSERIAL PRIMARY KEY).
struct Migration {
  int version = 0;
  const char* description = "";
  const char* sql = "";
};
const std::vector<Migration>& Migrations();

class ScoresDb {
 public:
  // Opens (creating it when missing) the database at `url`: a file path or `sqlite:PATH` for
  // SQLite, `postgresql://...` or `postgres://...` (libpq's URI) for PostgreSQL. Migrates the
  // schema up to `target_version` (tests use a lower one to build an old database). Throws
  // ScoresDbError "URL: reason" for an unreachable server, a file that is not a database, a
  // schema version newer than this build's, or a failed migration. A password in the URL is
  // never printed.
  static std::unique_ptr<ScoresDb> Open(const std::string& url,
                                        int target_version = kScoresSchemaVersion);
  virtual ~ScoresDb() = default;

  // The URL as given, without a password (for messages).
  const std::string& name() const { return name_; }
  bool is_postgresql() const { return postgresql_; }
  // The schema version of the database (after the migrations Open applied).
  int schema_version();

  // Runs one statement with `?` placeholders bound to `params` (in order). Throws
  // ScoresDbError naming the database and the statement's first words.
  virtual void Exec(const std::string& sql, const std::vector<SqlValue>& params = {}) = 0;
  // Runs a query and returns every row.
  virtual std::vector<SqlRow> Query(const std::string& sql,
                                    const std::vector<SqlValue>& params = {}) = 0;
  void Begin() { Exec("BEGIN"); }
  void Commit() { Exec("COMMIT"); }
  void Rollback();

 protected:
  ScoresDb(std::string name, bool postgresql) : name_(std::move(name)), postgresql_(postgresql) {}
  // Runs a script of ';'-separated statements without parameters.
  virtual void ExecScript(const std::string& sql) = 0;

 private:
  void Migrate(int target_version);

  std::string name_;
  bool postgresql_ = false;
};

// The URL with any password replaced by "***".
std::string RedactUrl(const std::string& url);

}  // namespace microdex::scores
