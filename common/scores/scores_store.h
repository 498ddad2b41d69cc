#pragma once
// What the instructor writes into the scores database and what the reports read from it, as
// plain rows over ScoresDb (scores_db.h). Every write is one transaction.

#include <cstdint>
#include <string>
#include <vector>

#include "common/scores/scores_db.h"

namespace microdex::scores {

struct SessionRow {
  std::string id;  // the station's session id (one station run)
  std::string course;
  std::string trainee;
  std::string scene;       // its name (the scene file's name without the folder)
  std::string scene_path;  // as the station named it
  std::string station;
  std::uint64_t seed = 0;
  double skill = -1;  // simulated trainee's skill; < 0: a real device (stored NULL)
  std::string device;
  std::string instructor_session;
  std::string recording;  // the session recording file ("" none)
  std::int64_t started_ns = 0;
  // Cue experiments ("" / 0 outside one).
  std::string experiment;
  std::string condition;
  int trial = 0;  // 1-based
};

struct ScoreTermRow {
  std::string metric;
  double value = 0, limit = 1, weight = 0, points = 0;
};

struct ScoreRow {
  bool is_final = false;
  std::uint64_t step = 0;
  double score = 0;
  std::string task;
  int outcome = 0;
  double progress = 0, duration_s = 0, time_in_contact_s = 0;
  std::uint32_t contacts = 0;
  double tremor_rms_m = 0, deviation_mean_m = 0;
  std::int64_t received_ns = 0;
  std::vector<ScoreTermRow> terms;
};

struct EventRow {
  std::uint64_t step = 0;
  std::string kind;  // net::TaskEventKindName
  std::uint64_t cue_id = 0;
  double value = 0;
  std::string text;
  std::int64_t received_ns = 0;
};

struct ExperimentRow {
  std::string name, file, scene;
  std::uint64_t seed = 0;
  int trials_per_trainee = 0;
  struct Condition {
    std::string name;
    std::string cues;  // the cue specs, ", " separated
  };
  std::vector<Condition> conditions;
  std::vector<std::pair<std::string, std::string>> assignments;  // trainee, condition
};

// A scored session as the reports read it.
struct ScoredSession {
  std::string id, course, trainee, scene, experiment, condition;
  int trial = 0;
  std::int64_t started_ns = 0;
  bool is_final = false;
  double score = 0;
};

// Inserts the course, trainee and scene when new, then the session (a session already there
// is left as it is: an instructor restarted in the middle of a run).
void AddSession(ScoresDb& db, const SessionRow& s);
// Replaces the session's score (and its terms) by this one.
void SaveScore(ScoresDb& db, const std::string& session, const ScoreRow& score);
void AddEvents(ScoresDb& db, const std::string& session, const std::vector<EventRow>& events);
void EndSession(ScoresDb& db, const std::string& session, std::int64_t ended_ns);

// Stores an experiment with its conditions and assignment. When it is already there (an
// instructor restarted), its stored assignment must equal this one, or ScoresDbError.
void SaveExperiment(ScoresDb& db, const ExperimentRow& e);
// The trials the trainee has started in the experiment so far (void ones, trial NULL, left out).
int CountTrials(ScoresDb& db, const std::string& experiment, const std::string& trainee);
// The experiment as stored (conditions in their order); throws ScoresDbError when absent.
ExperimentRow LoadExperiment(ScoresDb& db, const std::string& name);

// Every session with a score, by trainee then start time (course "" : every course;
// experiment "": every session).
std::vector<ScoredSession> LoadScoredSessions(ScoresDb& db, const std::string& course = "",
                                              const std::string& experiment = "");

}  // namespace microdex::scores
