#include "common/scores/scores_db.h"

#include <libpq-fe.h>
#include <sqlite3.h>
#include <time.h>

#include <cmath>
#include <cstdlib>
#include <string_view>

namespace microdex::scores {
namespace {

// Version 1: trainees, courses, scenes, sessions (one station run each), their latest score
// with its terms, and their task events. Version 2: cue experiments (their conditions and the
// assignment of trainees), and each session's experiment, condition and trial.
// Types are those both dialects accept: TEXT, BIGINT, DOUBLE PRECISION.
constexpr const char* kMigration1 = R"sql(
CREATE TABLE courses (
  name       TEXT PRIMARY KEY,
  created_ns BIGINT NOT NULL
);
CREATE TABLE trainees (
  name       TEXT PRIMARY KEY,
  created_ns BIGINT NOT NULL
);
CREATE TABLE scenes (
  name TEXT PRIMARY KEY,
  path TEXT NOT NULL
);
CREATE TABLE sessions (
  id                 TEXT PRIMARY KEY,
  course             TEXT NOT NULL REFERENCES courses(name),
  trainee            TEXT NOT NULL REFERENCES trainees(name),
  scene              TEXT NOT NULL REFERENCES scenes(name),
  station            TEXT NOT NULL,
  seed               BIGINT NOT NULL,
  skill              DOUBLE PRECISION,
  device             TEXT NOT NULL,
  instructor_session TEXT NOT NULL,
  recording          TEXT NOT NULL,
  started_ns         BIGINT NOT NULL,
  ended_ns           BIGINT
);
CREATE INDEX sessions_by_trainee ON sessions(trainee, started_ns);
CREATE TABLE scores (
  session           TEXT PRIMARY KEY REFERENCES sessions(id),
  is_final          BIGINT NOT NULL,
  step              BIGINT NOT NULL,
  score             DOUBLE PRECISION NOT NULL,
  task              TEXT NOT NULL,
  outcome           BIGINT NOT NULL,
  progress          DOUBLE PRECISION NOT NULL,
  duration_s        DOUBLE PRECISION NOT NULL,
  time_in_contact_s DOUBLE PRECISION NOT NULL,
  contacts          BIGINT NOT NULL,
  tremor_rms_m      DOUBLE PRECISION NOT NULL,
  deviation_mean_m  DOUBLE PRECISION NOT NULL,
  received_ns       BIGINT NOT NULL
);
CREATE TABLE score_terms (
  session     TEXT NOT NULL REFERENCES sessions(id),
  metric      TEXT NOT NULL,
  value       DOUBLE PRECISION NOT NULL,
  limit_value DOUBLE PRECISION NOT NULL,
  weight      DOUBLE PRECISION NOT NULL,
  points      DOUBLE PRECISION NOT NULL,
  PRIMARY KEY (session, metric)
);
CREATE TABLE events (
  id          {{serial}},
  session     TEXT NOT NULL REFERENCES sessions(id),
  step        BIGINT NOT NULL,
  kind        TEXT NOT NULL,
  cue_id      BIGINT NOT NULL,
  value       DOUBLE PRECISION NOT NULL,
  text        TEXT NOT NULL,
  received_ns BIGINT NOT NULL
);
CREATE INDEX events_by_session ON events(session, step)
)sql";

constexpr const char* kMigration2 = R"sql(
CREATE TABLE experiments (
  name               TEXT PRIMARY KEY,
  file               TEXT NOT NULL,
  scene              TEXT NOT NULL,
  seed               BIGINT NOT NULL,
  trials_per_trainee BIGINT NOT NULL,
  created_ns         BIGINT NOT NULL
);
CREATE TABLE experiment_conditions (
  experiment TEXT NOT NULL REFERENCES experiments(name),
  name       TEXT NOT NULL,
  position   BIGINT NOT NULL,
  cues       TEXT NOT NULL,
  PRIMARY KEY (experiment, name)
);
CREATE TABLE experiment_assignments (
  experiment TEXT NOT NULL REFERENCES experiments(name),
  trainee    TEXT NOT NULL REFERENCES trainees(name),
  condition  TEXT NOT NULL,
  PRIMARY KEY (experiment, trainee)
);
ALTER TABLE sessions ADD COLUMN experiment TEXT;
ALTER TABLE sessions ADD COLUMN condition TEXT;
ALTER TABLE sessions ADD COLUMN trial BIGINT
)sql";

std::int64_t RealtimeNowNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

std::string Replace(std::string text, std::string_view from, std::string_view to) {
  for (std::size_t at = text.find(from); at != std::string::npos;
       at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

// The statement's first words, for error messages.
std::string Head(const std::string& sql) {
  std::string h;
  for (char c : sql) {
    if (h.size() >= 40) {
      h += "...";
      break;
    }
    h += (c == '\n' || c == '\t') ? ' ' : c;
  }
  while (!h.empty() && h.front() == ' ') h.erase(h.begin());
  return h;
}

// libpq's messages span lines (and indent with tabs): one line for the apps' one-line errors.
void OneLine(std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '\n' || c == '\t' || c == '\r') c = ' ';
    if (c == ' ' && (out.empty() || out.back() == ' ')) continue;
    out += c;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  s = out;
}

bool StartsWith(const std::string& s, std::string_view prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// ---- SQLite ----

class SqliteDb final : public ScoresDb {
 public:
  SqliteDb(const std::string& url, const std::string& path) : ScoresDb(url, false) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw ScoresDbError(url + ": cannot open: " + why);
    }
    sqlite3_busy_timeout(db_, 5000);  // two instructors of one course may share the file
    // WAL + synchronous=NORMAL: a commit does not wait for the disk (a killed instructor keeps
    // every committed row; a power cut may lose the last ones).
    ExecScript("PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON");
  }
  ~SqliteDb() override { sqlite3_close(db_); }
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;

  void Exec(const std::string& sql, const std::vector<SqlValue>& params) override {
    Run(sql, params, nullptr);
  }
  std::vector<SqlRow> Query(const std::string& sql, const std::vector<SqlValue>& params) override {
    std::vector<SqlRow> rows;
    Run(sql, params, &rows);
    return rows;
  }

 protected:
  void ExecScript(const std::string& sql) override {
    char* err = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
      const std::string why = err ? err : sqlite3_errmsg(db_);
      sqlite3_free(err);
      throw ScoresDbError(name() + ": " + Head(sql) + ": " + why);
    }
  }

 private:
  void Run(const std::string& sql, const std::vector<SqlValue>& params, std::vector<SqlRow>* rows) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &st, nullptr) != SQLITE_OK) Fail(sql);
    for (std::size_t i = 0; i < params.size(); ++i) {
      const int at = static_cast<int>(i + 1);
      const SqlValue& v = params[i];
      if (const auto* n = std::get_if<std::int64_t>(&v)) {
        sqlite3_bind_int64(st, at, *n);
      } else if (const auto* d = std::get_if<double>(&v)) {
        if (std::isfinite(*d)) {
          sqlite3_bind_double(st, at, *d);
        } else {
          sqlite3_bind_null(st, at);
        }
      } else if (const auto* s = std::get_if<std::string>(&v)) {
        sqlite3_bind_text(st, at, s->data(), static_cast<int>(s->size()), SQLITE_TRANSIENT);
      } else {
        sqlite3_bind_null(st, at);
      }
    }
    for (;;) {
      const int rc = sqlite3_step(st);
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) {
        sqlite3_finalize(st);
        Fail(sql);
      }
      if (!rows) continue;
      SqlRow row;
      const int n = sqlite3_column_count(st);
      for (int c = 0; c < n; ++c) {
        if (sqlite3_column_type(st, c) == SQLITE_NULL) {
          row.cells.emplace_back(std::nullopt);
        } else {
          const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(st, c));
          row.cells.emplace_back(
              std::string(text, static_cast<std::size_t>(sqlite3_column_bytes(st, c))));
        }
      }
      rows->push_back(std::move(row));
    }
    sqlite3_finalize(st);
  }
  [[noreturn]] void Fail(const std::string& sql) const {
    throw ScoresDbError(name() + ": " + Head(sql) + ": " + sqlite3_errmsg(db_));
  }

  sqlite3* db_ = nullptr;
};

// ---- PostgreSQL (libpq) ----

class PostgresDb final : public ScoresDb {
 public:
  PostgresDb(const std::string& url, const std::string& conninfo) : ScoresDb(RedactUrl(url), true) {
    // connect_timeout bounds the wait for an unreachable host (libpq's default is forever).
    std::string info = conninfo;
    if (info.find("connect_timeout") == std::string::npos) {
      info += (info.find('?') == std::string::npos ? "?" : "&");
      info += "connect_timeout=5";
    }
    conn_ = PQconnectdb(info.c_str());
    if (conn_ == nullptr || PQstatus(conn_) != CONNECTION_OK) {
      std::string why = conn_ ? PQerrorMessage(conn_) : "out of memory";
      OneLine(why);
      PQfinish(conn_);
      conn_ = nullptr;
      throw ScoresDbError(name() + ": cannot connect: " + why);
    }
    // Notices (e.g. "relation already exists, skipping") are not errors: keep them quiet.
    PQsetNoticeProcessor(
        conn_, [](void*, const char*) {}, nullptr);
  }
  ~PostgresDb() override { PQfinish(conn_); }
  PostgresDb(const PostgresDb&) = delete;
  PostgresDb& operator=(const PostgresDb&) = delete;

  void Exec(const std::string& sql, const std::vector<SqlValue>& params) override {
    Run(sql, params, nullptr);
  }
  std::vector<SqlRow> Query(const std::string& sql, const std::vector<SqlValue>& params) override {
    std::vector<SqlRow> rows;
    Run(sql, params, &rows);
    return rows;
  }

 protected:
  void ExecScript(const std::string& sql) override {
    PGresult* r = PQexec(conn_, sql.c_str());
    Check(r, sql);
    PQclear(r);
  }

 private:
  void Check(PGresult* r, const std::string& sql) const {
    const ExecStatusType s = PQresultStatus(r);
    if (s == PGRES_COMMAND_OK || s == PGRES_TUPLES_OK) return;
    std::string why = r ? PQresultErrorMessage(r) : PQerrorMessage(conn_);
    PQclear(r);
    OneLine(why);
    throw ScoresDbError(name() + ": " + Head(sql) + ": " + why);
  }
  void Run(const std::string& sql, const std::vector<SqlValue>& params, std::vector<SqlRow>* rows) {
    // `?` → `$n` (the statements here have no `?` inside string literals).
    std::string text;
    int n = 0;
    for (char c : sql) {
      if (c == '?') {
        text += '$' + std::to_string(++n);
      } else {
        text += c;
      }
    }
    std::vector<std::string> values(params.size());
    std::vector<const char*> ptrs(params.size(), nullptr);
    for (std::size_t i = 0; i < params.size(); ++i) {
      const SqlValue& v = params[i];
      if (const auto* k = std::get_if<std::int64_t>(&v)) {
        values[i] = std::to_string(*k);
      } else if (const auto* d = std::get_if<double>(&v)) {
        if (!std::isfinite(*d)) continue;  // NULL
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", *d);
        values[i] = buf;
      } else if (const auto* s = std::get_if<std::string>(&v)) {
        values[i] = *s;
      } else {
        continue;  // NULL
      }
      ptrs[i] = values[i].c_str();
    }
    PGresult* r = PQexecParams(conn_, text.c_str(), static_cast<int>(params.size()), nullptr,
                               ptrs.data(), nullptr, nullptr, 0);
    Check(r, sql);
    if (rows) {
      const int nrows = PQntuples(r), ncols = PQnfields(r);
      for (int i = 0; i < nrows; ++i) {
        SqlRow row;
        for (int c = 0; c < ncols; ++c) {
          if (PQgetisnull(r, i, c)) {
            row.cells.emplace_back(std::nullopt);
          } else {
            row.cells.emplace_back(
                std::string(PQgetvalue(r, i, c), static_cast<std::size_t>(PQgetlength(r, i, c))));
          }
        }
        rows->push_back(std::move(row));
      }
    }
    PQclear(r);
  }

  PGconn* conn_ = nullptr;
};

}  // namespace

std::string SqlRow::Text(std::size_t i) const { return cells.at(i).value_or(""); }

std::int64_t SqlRow::Int(std::size_t i) const {
  if (!cells.at(i)) return 0;
  return std::strtoll(cells[i]->c_str(), nullptr, 10);
}

double SqlRow::Real(std::size_t i) const {
  if (!cells.at(i)) return NAN;
  return std::strtod(cells[i]->c_str(), nullptr);
}

const std::vector<Migration>& Migrations() {
  static const std::vector<Migration> m = {
      {1, "trainees, courses, scenes, sessions, scores, score terms, events", kMigration1},
      {2, "cue experiments: conditions, assignments; session experiment, condition, trial",
       kMigration2},
  };
  return m;
}

std::string RedactUrl(const std::string& url) {
  // scheme://user:password@host...: the password replaced.
  const std::size_t scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  const std::size_t at = url.find('@', scheme + 3);
  if (at == std::string::npos) return url;
  const std::size_t colon = url.find(':', scheme + 3);
  if (colon == std::string::npos || colon > at) return url;
  return url.substr(0, colon + 1) + "***" + url.substr(at);
}

void ScoresDb::Rollback() {
  try {
    Exec("ROLLBACK");
  } catch (const ScoresDbError&) {
    // Nothing to roll back (no transaction open): the first error is the one reported.
  }
}

int ScoresDb::schema_version() {
  const auto rows = Query("SELECT MAX(version) FROM schema_version");
  return rows.empty() ? 0 : static_cast<int>(rows[0].Int(0));
}

void ScoresDb::Migrate(int target_version) {
  ExecScript(
      "CREATE TABLE IF NOT EXISTS schema_version (version BIGINT PRIMARY KEY, description "
      "TEXT NOT NULL, applied_ns BIGINT NOT NULL)");
  const int current = schema_version();
  if (current > kScoresSchemaVersion) {
    throw ScoresDbError(name() + ": scores database schema version " + std::to_string(current) +
                        " is newer than this build's (" + std::to_string(kScoresSchemaVersion) +
                        "): use a newer microdex");
  }
  for (const Migration& m : Migrations()) {
    if (m.version <= current || m.version > target_version) continue;
    const std::string sql =
        Replace(m.sql, "{{serial}}",
                postgresql_ ? "BIGSERIAL PRIMARY KEY" : "INTEGER PRIMARY KEY AUTOINCREMENT");
    Begin();
    try {
      ExecScript(sql);
      Exec("INSERT INTO schema_version(version, description, applied_ns) VALUES (?, ?, ?)",
           {std::int64_t{m.version}, std::string(m.description), RealtimeNowNs()});
      Commit();
    } catch (const ScoresDbError& e) {
      Rollback();
      throw ScoresDbError(std::string(e.what()) + " (migration to version " +
                          std::to_string(m.version) + ")");
    }
  }
}

std::unique_ptr<ScoresDb> ScoresDb::Open(const std::string& url, int target_version) {
  if (url.empty()) throw ScoresDbError("--db: expected a file path or a postgresql:// URL");
  std::unique_ptr<ScoresDb> db;
  if (StartsWith(url, "postgresql://") || StartsWith(url, "postgres://")) {
    db = std::make_unique<PostgresDb>(url, url);
  } else if (url.find("://") != std::string::npos) {
    throw ScoresDbError(RedactUrl(url) +
                        ": unknown database URL scheme (expected a file path, sqlite:PATH or "
                        "postgresql://...)");
  } else {
    const std::string path = StartsWith(url, "sqlite:") ? url.substr(7) : url;
    db = std::make_unique<SqliteDb>(url, path);
  }
  db->Migrate(target_version);
  return db;
}

}  // namespace microdex::scores
