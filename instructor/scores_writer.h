#pragma once
// Writes what the instructor sees into the scores database (microdex-instructor --db URL):
// each station run as a session (its trainee from StationInfo, the course, the scene), its
// score (the live one, replaced until the final one arrives) and its task events. With an
// experiment (--experiment FILE.yaml) it also stores the experiment and its assignment, and at
// each trial's start (a station of an assigned trainee appearing with a new session) sends
// that station its condition's cues and tags the session with experiment, condition and trial.
//
// Called from microdex-instructor's main loop (not the DDS thread): the database may be a
// remote PostgreSQL server.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/scores/experiment.h"
#include "common/scores/scores_db.h"
#include "common/scores/scores_store.h"
#include "instructor/instructor.h"

namespace microdex::instructor {

struct ScoresWriterOptions {
  std::string url;                 // --db
  std::string course = "default";  // --course
  std::string recording;           // --record file ("" none); a recording running is named first
  std::optional<scores::ExperimentDef> experiment;
};

class ScoresWriter {
 public:
  // Opens the database (migrating it) and stores the experiment. Throws ScoresDbError.
  ScoresWriter(const ScoresWriterOptions& options, Instructor& console);

  // One pass: new sessions (their trial cues sent first, before any database write), the
  // final scores taken from the console (Instructor::TakeFinalScores), the live scores of the
  // registry, then `events` (the task events taken from the console since the last pass).
  // Returns one line per thing worth printing.
  std::vector<std::string> Update(const std::vector<StationView>& stations,
                                  const std::vector<net::TaskEvent>& events,
                                  const std::vector<net::Score>& final_scores);
  // Writes the latest score of every session and marks the sessions ended.
  void Finish(const std::vector<StationView>& stations);

  // With an experiment: every trainee has a final score in each of its trials.
  bool ExperimentDone() const;
  // The course's sessions with a final score, by trainee then start time (the console's plot
  // of past sessions). Throws ScoresDbError.
  std::vector<scores::ScoredSession> FinalScores();
  const std::map<std::string, std::string>& assignment() const { return assignment_; }

 private:
  struct Tracked {
    std::string session;
    std::string trainee;
    std::uint64_t score_step = 0;
    bool score_final = false;
    bool counted = false;  // a trial of the experiment
    int trial = 0;
    bool ended = false;
    std::int64_t ended_ns = 0;  // when it was seen to end (realtime)
    bool voided = false;        // ended without a final score: its trial is run again
    std::int64_t score_saved_ns = 0;
  };
  void SaveScore(const net::Score& s, Tracked& t);
  // The tracked run of a session (current or earlier); nullptr when not tracked.
  Tracked* FindSession(const std::string& session);
  // A counted trial that ended without a final score (its StationInfo, events or score never
  // reached the instructor) is void: its later trials move down one, and the trainee's next
  // run repeats it.
  void VoidUnfinishedTrials(std::int64_t now_ns, std::vector<std::string>& lines);

  ScoresWriterOptions options_;
  Instructor& console_;
  std::unique_ptr<scores::ScoresDb> db_;
  std::map<std::string, std::string> assignment_;      // trainee → condition
  std::map<std::string, Tracked> stations_;            // station id → its current session
  std::map<std::string, Tracked> past_;                // session id → an earlier run
  std::set<std::string> sessions_;                     // sessions stored
  std::vector<net::TaskEvent> pending_events_;         // of sessions not stored yet
  std::vector<net::Score> pending_finals_;             // likewise
  std::map<std::string, std::int64_t> awaiting_info_;  // session seen in DeviceInput → when
  std::map<std::string, int> started_trials_;          // trainee → trials started
  std::map<std::string, int> finished_trials_;         // trainee → trials with a final score
};

}  // namespace microdex::instructor
