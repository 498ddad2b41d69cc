// The scores database on SQLite and on a real PostgreSQL server (started by the test on a
// loopback port in a temporary folder): the same migrations, the same round trip, a schema
// from the future refused, bad URLs and unreachable servers reported clearly.

#include "common/scores/scores_db.h"

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "common/scores/scores_store.h"
#include "tests/support/postgres_server.h"

namespace microdex::scores {
namespace {

std::string TmpDir() {
  std::string dir = "/tmp/microdex-scores-XXXXXX";
  return mkdtemp(dir.data()) ? dir : "/tmp";
}

// The round trip every backend must pass: a session, its live then final score, its events,
// read back by the reports' query.
void RoundTrip(ScoresDb& db) {
  SessionRow s;
  s.id = "st1-100-1";
  s.course = "micro-2026";
  s.trainee = "ana";
  s.scene = "tremor_hold.yaml";
  s.scene_path = "assets/scenes/tremor_hold.yaml";
  s.station = "st1";
  s.seed = 42;
  s.skill = 0.4;
  s.device = "sim";
  s.instructor_session = "instructor-1";
  s.started_ns = 1'000;
  AddSession(db, s);
  AddSession(db, s);  // again (an instructor restarted): kept as it is
  ScoreRow live;
  live.score = 40;
  live.step = 500;
  live.task = "tremor_hold";
  live.terms = {{"tremor_rms_m", 30e-6, 80e-6, 2, 1.25}};
  SaveScore(db, s.id, live);
  ScoreRow final_score = live;
  final_score.is_final = true;
  final_score.score = 61.5;
  final_score.step = 1499;
  final_score.terms.push_back({"drift_m", 1e-4, 4e-4, 2, 1.5});
  SaveScore(db, s.id, final_score);
  AddEvents(db, s.id, {{0, "task-start", 0, 0, "tremor-hold", 5}, {1499, "task-end", 0, 1, "", 6}});
  EndSession(db, s.id, 2'000);
  s.id = "st1-200-1";
  s.started_ns = 3'000;
  AddSession(db, s);  // a second session without a score: not in the scored list

  const auto scored = LoadScoredSessions(db, "micro-2026");
  ASSERT_EQ(scored.size(), 1u);
  EXPECT_EQ(scored[0].trainee, "ana");
  EXPECT_TRUE(scored[0].is_final);
  EXPECT_DOUBLE_EQ(scored[0].score, 61.5);
  EXPECT_TRUE(LoadScoredSessions(db, "another-course").empty());
  const auto terms = db.Query(
      "SELECT metric, value FROM score_terms WHERE session = ? ORDER BY "
      "metric",
      {std::string("st1-100-1")});
  ASSERT_EQ(terms.size(), 2u);
  EXPECT_EQ(terms[0].Text(0), "drift_m");
  EXPECT_DOUBLE_EQ(terms[1].Real(1), 30e-6);
  const auto events =
      db.Query("SELECT kind, text FROM events WHERE session = ? ORDER BY step", {"st1-100-1"});
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].Text(1), "tremor-hold");
  const auto skill = db.Query("SELECT skill, ended_ns FROM sessions WHERE id = 'st1-100-1'");
  EXPECT_DOUBLE_EQ(skill.at(0).Real(0), 0.4);
  EXPECT_EQ(skill.at(0).Int(1), 2'000);

  ExperimentRow e;
  e.name = "pilot";
  e.file = "pilot.yaml";
  e.scene = "tremor_hold.yaml";
  e.seed = 3;
  e.trials_per_trainee = 2;
  e.conditions = {{"none", ""}, {"audio", "audio_click:0.8"}};
  e.assignments = {{"ana", "audio"}, {"ben", "none"}};
  SaveExperiment(db, e);
  SaveExperiment(db, e);  // the same again: accepted
  const ExperimentRow back = LoadExperiment(db, "pilot");
  ASSERT_EQ(back.conditions.size(), 2u);
  EXPECT_EQ(back.conditions[1].name, "audio");
  EXPECT_EQ(back.assignments, e.assignments);
  e.assignments = {{"ana", "none"}, {"ben", "audio"}};
  EXPECT_THROW(SaveExperiment(db, e), ScoresDbError);  // another assignment under that name
  EXPECT_THROW(LoadExperiment(db, "absent"), ScoresDbError);
}

// An old database (version 1, with a session), then opened by this build: migrated to the
// current version with its rows kept.
void MigratesFromVersion1(const std::string& url) {
  {
    const auto v1 = ScoresDb::Open(url, 1);
    EXPECT_EQ(v1->schema_version(), 1);
    v1->Exec("INSERT INTO courses(name, created_ns) VALUES ('c', 1)");
    v1->Exec("INSERT INTO trainees(name, created_ns) VALUES ('t', 1)");
    v1->Exec("INSERT INTO scenes(name, path) VALUES ('s', 's')");
    v1->Exec(
        "INSERT INTO sessions(id, course, trainee, scene, station, seed, device, "
        "instructor_session, recording, started_ns) VALUES ('old', 'c', 't', 's', 'st', 1, "
        "'sim', 'i', '', 5)");
    // Version 2's columns are not there yet.
    EXPECT_THROW(v1->Query("SELECT trial FROM sessions"), ScoresDbError);
  }
  const auto db = ScoresDb::Open(url);
  EXPECT_EQ(db->schema_version(), kScoresSchemaVersion);
  const auto rows = db->Query("SELECT id, trial FROM sessions");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].Text(0), "old");
  EXPECT_TRUE(rows[0].IsNull(1));
  const auto versions = db->Query("SELECT version FROM schema_version ORDER BY version");
  ASSERT_EQ(versions.size(), static_cast<std::size_t>(kScoresSchemaVersion));
}

void RefusesTheFuture(const std::string& url) {
  {
    const auto db = ScoresDb::Open(url);
    db->Exec(
        "INSERT INTO schema_version(version, description, applied_ns) VALUES (?, ?, ?)",
        {std::int64_t{kScoresSchemaVersion + 1}, std::string("from the future"), std::int64_t{1}});
  }
  try {
    ScoresDb::Open(url);
    FAIL() << "a newer schema was accepted";
  } catch (const ScoresDbError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("schema version " + std::to_string(kScoresSchemaVersion + 1)),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("newer than this build"), std::string::npos) << what;
  }
}

TEST(ScoresDbSqlite, FreshDatabaseHasTheCurrentSchemaAndRoundTrips) {
  const std::string dir = TmpDir();
  const auto db = ScoresDb::Open(dir + "/course.db");
  EXPECT_FALSE(db->is_postgresql());
  EXPECT_EQ(db->schema_version(), kScoresSchemaVersion);
  RoundTrip(*db);
  // sqlite:PATH names the same file.
  EXPECT_EQ(LoadScoredSessions(*ScoresDb::Open("sqlite:" + dir + "/course.db")).size(), 1u);
}

TEST(ScoresDbSqlite, MigratesAnOldDatabase) { MigratesFromVersion1(TmpDir() + "/old.db"); }

TEST(ScoresDbSqlite, RefusesASchemaFromTheFuture) { RefusesTheFuture(TmpDir() + "/future.db"); }

TEST(ScoresDbSqlite, BadFilesAndUrlsAreNamed) {
  const std::string dir = TmpDir();
  const std::string text = dir + "/notes.txt";
  std::ofstream(text) << "these are not the scores you are looking for\n" << std::string(4096, 'x');
  try {
    ScoresDb::Open(text);
    FAIL();
  } catch (const ScoresDbError& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a database"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ScoresDb::Open(dir + "/missing-folder/course.db"), ScoresDbError);
  try {
    ScoresDb::Open("mysql://root:secret@host/db");
    FAIL();
  } catch (const ScoresDbError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown database URL scheme"), std::string::npos);
    EXPECT_EQ(std::string(e.what()).find("secret"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ScoresDb::Open(""), ScoresDbError);
}

TEST(ScoresDbPostgres, UnreachableServerIsAClearError) {
  // Port 1 on loopback: nothing listens there.
  try {
    ScoresDb::Open("postgresql://trainer:hunter2@127.0.0.1:1/scores");
    FAIL();
  } catch (const ScoresDbError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("postgresql://trainer:***@127.0.0.1:1/scores: cannot connect"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find("hunter2"), std::string::npos) << what;
  }
}

class PostgresServer : public testing::PostgresServerTest {};

TEST_F(PostgresServer, FreshDatabaseHasTheCurrentSchemaAndRoundTrips) {
  const auto db = ScoresDb::Open(NewDatabase("course"));
  EXPECT_TRUE(db->is_postgresql());
  EXPECT_EQ(db->schema_version(), kScoresSchemaVersion);
  RoundTrip(*db);
}

TEST_F(PostgresServer, MigratesAnOldDatabase) { MigratesFromVersion1(NewDatabase("old")); }

TEST_F(PostgresServer, RefusesASchemaFromTheFuture) { RefusesTheFuture(NewDatabase("future")); }

TEST_F(PostgresServer, UnknownDatabaseIsNamed) {
  try {
    ScoresDb::Open(Url("nosuchdb"));
    FAIL();
  } catch (const ScoresDbError& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchdb"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot connect"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace microdex::scores
