#include "common/scores/scores_store.h"

#include <time.h>

#include <algorithm>

namespace microdex::scores {
namespace {

std::int64_t RealtimeNowNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

SqlValue TextOrNull(const std::string& s) {
  if (s.empty()) return std::monostate{};
  return s;
}

// Runs `body` in one transaction (rolled back when it throws).
template <class F>
void InTransaction(ScoresDb& db, F&& body) {
  db.Begin();
  try {
    body();
    db.Commit();
  } catch (...) {
    db.Rollback();
    throw;
  }
}

}  // namespace

void AddSession(ScoresDb& db, const SessionRow& s) {
  const std::int64_t now = RealtimeNowNs();
  InTransaction(db, [&] {
    db.Exec("INSERT INTO courses(name, created_ns) VALUES (?, ?) ON CONFLICT (name) DO NOTHING",
            {s.course, now});
    db.Exec("INSERT INTO trainees(name, created_ns) VALUES (?, ?) ON CONFLICT (name) DO NOTHING",
            {s.trainee, now});
    db.Exec("INSERT INTO scenes(name, path) VALUES (?, ?) ON CONFLICT (name) DO NOTHING",
            {s.scene, s.scene_path});
    db.Exec(
        "INSERT INTO sessions(id, course, trainee, scene, station, seed, skill, device, "
        "instructor_session, recording, started_ns, experiment, condition, trial) VALUES (?, ?, "
        "?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (id) DO NOTHING",
        {s.id, s.course, s.trainee, s.scene, s.station, static_cast<std::int64_t>(s.seed),
         s.skill < 0 ? SqlValue{} : SqlValue{s.skill}, s.device, s.instructor_session, s.recording,
         s.started_ns, TextOrNull(s.experiment), TextOrNull(s.condition),
         s.trial > 0 ? SqlValue{std::int64_t{s.trial}} : SqlValue{}});
  });
}

void SaveScore(ScoresDb& db, const std::string& session, const ScoreRow& sc) {
  InTransaction(db, [&] {
    db.Exec("DELETE FROM scores WHERE session = ?", {session});
    db.Exec(
        "INSERT INTO scores(session, is_final, step, score, task, outcome, progress, "
        "duration_s, time_in_contact_s, contacts, tremor_rms_m, deviation_mean_m, received_ns) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
        {session, std::int64_t{sc.is_final ? 1 : 0}, static_cast<std::int64_t>(sc.step), sc.score,
         sc.task, std::int64_t{sc.outcome}, sc.progress, sc.duration_s, sc.time_in_contact_s,
         std::int64_t{sc.contacts}, sc.tremor_rms_m, sc.deviation_mean_m, sc.received_ns});
    db.Exec("DELETE FROM score_terms WHERE session = ?", {session});
    for (const ScoreTermRow& t : sc.terms) {
      db.Exec(
          "INSERT INTO score_terms(session, metric, value, limit_value, weight, points) VALUES "
          "(?, ?, ?, ?, ?, ?) ON CONFLICT (session, metric) DO NOTHING",
          {session, t.metric, t.value, t.limit, t.weight, t.points});
    }
  });
}

void AddEvents(ScoresDb& db, const std::string& session, const std::vector<EventRow>& events) {
  if (events.empty()) return;
  InTransaction(db, [&] {
    for (const EventRow& e : events) {
      db.Exec(
          "INSERT INTO events(session, step, kind, cue_id, value, text, received_ns) VALUES (?, "
          "?, ?, ?, ?, ?, ?)",
          {session, static_cast<std::int64_t>(e.step), e.kind, static_cast<std::int64_t>(e.cue_id),
           e.value, e.text, e.received_ns});
    }
  });
}

void EndSession(ScoresDb& db, const std::string& session, std::int64_t ended_ns) {
  db.Exec("UPDATE sessions SET ended_ns = ? WHERE id = ?", {ended_ns, session});
}

void SaveExperiment(ScoresDb& db, const ExperimentRow& e) {
  const std::int64_t now = RealtimeNowNs();
  InTransaction(db, [&] {
    const auto existing = db.Query(
        "SELECT trainee, condition FROM experiment_assignments WHERE "
        "experiment = ? ORDER BY trainee",
        {e.name});
    if (!existing.empty()) {
      std::vector<std::pair<std::string, std::string>> want = e.assignments;
      std::sort(want.begin(), want.end());
      bool same = existing.size() == want.size();
      for (std::size_t i = 0; same && i < want.size(); ++i) {
        same = existing[i].Text(0) == want[i].first && existing[i].Text(1) == want[i].second;
      }
      if (!same) {
        throw ScoresDbError(db.name() + ": experiment '" + e.name +
                            "' is already stored with another assignment of trainees (another "
                            "seed, conditions or trainees): give the changed experiment a new "
                            "name");
      }
      return;
    }
    db.Exec(
        "INSERT INTO experiments(name, file, scene, seed, trials_per_trainee, created_ns) VALUES "
        "(?, ?, ?, ?, ?, ?) ON CONFLICT (name) DO NOTHING",
        {e.name, e.file, e.scene, static_cast<std::int64_t>(e.seed),
         std::int64_t{e.trials_per_trainee}, now});
    for (std::size_t i = 0; i < e.conditions.size(); ++i) {
      db.Exec(
          "INSERT INTO experiment_conditions(experiment, name, position, cues) VALUES (?, ?, ?, "
          "?)",
          {e.name, e.conditions[i].name, static_cast<std::int64_t>(i), e.conditions[i].cues});
    }
    for (const auto& [trainee, condition] : e.assignments) {
      db.Exec("INSERT INTO trainees(name, created_ns) VALUES (?, ?) ON CONFLICT (name) DO NOTHING",
              {trainee, now});
      db.Exec("INSERT INTO experiment_assignments(experiment, trainee, condition) VALUES (?, ?, ?)",
              {e.name, trainee, condition});
    }
  });
}

int CountTrials(ScoresDb& db, const std::string& experiment, const std::string& trainee) {
  const auto rows = db.Query(
      "SELECT COUNT(*) FROM sessions WHERE experiment = ? AND trainee = ? AND trial IS NOT NULL",
      {experiment, trainee});
  return rows.empty() ? 0 : static_cast<int>(rows[0].Int(0));
}

ExperimentRow LoadExperiment(ScoresDb& db, const std::string& name) {
  const auto rows = db.Query(
      "SELECT name, file, scene, seed, trials_per_trainee FROM experiments WHERE name = ?", {name});
  if (rows.empty()) {
    throw ScoresDbError(db.name() + ": no experiment '" + name +
                        "' (run microdex-instructor --experiment first)");
  }
  ExperimentRow e;
  e.name = rows[0].Text(0);
  e.file = rows[0].Text(1);
  e.scene = rows[0].Text(2);
  e.seed = static_cast<std::uint64_t>(rows[0].Int(3));
  e.trials_per_trainee = static_cast<int>(rows[0].Int(4));
  for (const SqlRow& r : db.Query("SELECT name, cues FROM experiment_conditions WHERE experiment "
                                  "= ? ORDER BY position",
                                  {name})) {
    e.conditions.push_back({r.Text(0), r.Text(1)});
  }
  for (const SqlRow& r : db.Query("SELECT trainee, condition FROM experiment_assignments WHERE "
                                  "experiment = ? ORDER BY trainee",
                                  {name})) {
    e.assignments.emplace_back(r.Text(0), r.Text(1));
  }
  return e;
}

std::vector<ScoredSession> LoadScoredSessions(ScoresDb& db, const std::string& course,
                                              const std::string& experiment) {
  std::string sql =
      "SELECT s.id, s.course, s.trainee, s.scene, s.experiment, s.condition, s.trial, "
      "s.started_ns, c.is_final, c.score FROM sessions s JOIN scores c ON c.session = s.id";
  std::vector<SqlValue> params;
  std::string where;
  if (!course.empty()) {
    where += " s.course = ?";
    params.emplace_back(course);
  }
  if (!experiment.empty()) {
    where += std::string(where.empty() ? "" : " AND") + " s.experiment = ?";
    params.emplace_back(experiment);
  }
  if (!where.empty()) sql += " WHERE" + where;
  sql += " ORDER BY s.trainee, s.started_ns, s.id";
  std::vector<ScoredSession> out;
  for (const SqlRow& r : db.Query(sql, params)) {
    ScoredSession s;
    s.id = r.Text(0);
    s.course = r.Text(1);
    s.trainee = r.Text(2);
    s.scene = r.Text(3);
    s.experiment = r.Text(4);
    s.condition = r.Text(5);
    s.trial = static_cast<int>(r.Int(6));
    s.started_ns = r.Int(7);
    s.is_final = r.Int(8) != 0;
    s.score = r.Real(9);
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace microdex::scores
