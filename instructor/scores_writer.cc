#include "instructor/scores_writer.h"

#include <time.h>

#include <cstdio>

#include "common/scores/scores_store.h"

namespace microdex::instructor {
namespace {

std::int64_t RealtimeNowNs() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

std::string FileName(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// How long after a counted trial's end its final score may still arrive before the trial is
// void.
constexpr std::int64_t kFinalScoreGrace_ns = 3'000'000'000;

// How long a new session seen in DeviceInput waits for its StationInfo.
constexpr std::int64_t kStationInfoWait_ns = 1'000'000'000;

// A live score is written at most this often (the final one at once).
constexpr std::int64_t kLiveScorePeriod_ns = 1'000'000'000;

}  // namespace

ScoresWriter::ScoresWriter(const ScoresWriterOptions& options, Instructor& console)
    : options_(options), console_(console), db_(scores::ScoresDb::Open(options.url)) {
  if (!options_.experiment) return;
  const scores::ExperimentDef& e = *options_.experiment;
  assignment_ = scores::AssignConditions(e);
  scores::ExperimentRow row;
  row.name = e.name;
  row.file = e.file;
  row.scene = e.scene;
  row.seed = e.seed;
  row.trials_per_trainee = e.trials_per_trainee;
  for (const auto& c : e.conditions) {
    std::string cues;
    for (const auto& s : c.cue_specs) cues += (cues.empty() ? "" : ", ") + s;
    row.conditions.push_back({c.name, cues});
  }
  for (const auto& [trainee, condition] : assignment_)
    row.assignments.emplace_back(trainee, condition);
  scores::SaveExperiment(*db_, row);
  // Trials already finished (an instructor restarted in the middle of the experiment).
  for (const auto& s : scores::LoadScoredSessions(*db_, "", e.name)) {
    if (s.is_final && s.trial > 0) ++finished_trials_[s.trainee];
  }
  for (const auto& [trainee, condition] : assignment_) {
    started_trials_[trainee] = scores::CountTrials(*db_, e.name, trainee);
  }
}

bool ScoresWriter::ExperimentDone() const {
  if (!options_.experiment) return false;
  for (const auto& [trainee, condition] : assignment_) {
    auto it = finished_trials_.find(trainee);
    if (it == finished_trials_.end() || it->second < options_.experiment->trials_per_trainee) {
      return false;
    }
  }
  return true;
}

ScoresWriter::Tracked* ScoresWriter::FindSession(const std::string& session) {
  for (auto& [station, t] : stations_) {
    if (t.session == session) return &t;
  }
  auto it = past_.find(session);
  return it == past_.end() ? nullptr : &it->second;
}

void ScoresWriter::VoidUnfinishedTrials(std::int64_t now_ns, std::vector<std::string>& lines) {
  const auto check = [&](Tracked& t) {
    if (!t.counted || t.voided || t.score_final || t.ended_ns == 0 ||
        now_ns - t.ended_ns < kFinalScoreGrace_ns) {
      return;
    }
    t.voided = true;
    const std::string& experiment = options_.experiment->name;
    db_->Begin();
    try {
      db_->Exec("UPDATE sessions SET trial = NULL WHERE id = ?", {t.session});
      db_->Exec(
          "UPDATE sessions SET trial = trial - 1 WHERE experiment = ? AND trainee = ? AND trial "
          "> ?",
          {experiment, t.trainee, std::int64_t{t.trial}});
      db_->Commit();
    } catch (...) {
      db_->Rollback();
      throw;
    }
    for (auto* group : {&stations_, &past_}) {
      for (auto& [key, other] : *group) {
        if (other.counted && !other.voided && other.trainee == t.trainee && other.trial > t.trial) {
          --other.trial;
        }
      }
    }
    --started_trials_[t.trainee];
    lines.push_back("experiment " + experiment + ": " + t.trainee + " trial " +
                    std::to_string(t.trial) + " void (session " + t.session +
                    " ended without a final score); the next run repeats it");
  };
  for (auto& [station, t] : stations_) check(t);
  for (auto& [session, t] : past_) check(t);
}

void ScoresWriter::SaveScore(const net::Score& s, Tracked& t) {
  if (t.score_final) return;
  const std::int64_t now = RealtimeNowNs();
  scores::ScoreRow r;
  r.is_final = s.is_final;
  r.step = s.header.step;
  r.score = s.score;
  r.task = s.task;
  r.outcome = s.outcome;
  r.progress = s.progress;
  r.duration_s = s.duration_s;
  r.time_in_contact_s = s.time_in_contact_s;
  r.contacts = s.contacts;
  r.tremor_rms_m = s.tremor_rms_m;
  r.deviation_mean_m = s.deviation_mean_m;
  r.received_ns = now;
  for (const net::ScoreTerm& term : s.terms) {
    r.terms.push_back({term.metric, term.value, term.limit, term.weight, term.points});
  }
  scores::SaveScore(*db_, t.session, r);
  t.score_step = s.header.step;
  t.score_saved_ns = now;
  if (s.is_final) {
    t.score_final = true;
    if (t.counted && !t.voided) ++finished_trials_[t.trainee];
  }
}

std::vector<std::string> ScoresWriter::Update(const std::vector<StationView>& stations,
                                              const std::vector<net::TaskEvent>& events,
                                              const std::vector<net::Score>& final_scores) {
  std::vector<std::string> lines;
  // New sessions: each trial's cues go out first, the database writes after.
  std::vector<scores::SessionRow> new_sessions;
  std::vector<std::string> ended;
  const std::int64_t pass_ns = RealtimeNowNs();
  for (const StationView& v : stations) {
    std::string session = v.info.header.session_id;
    if (session.empty()) continue;  // no StationInfo yet
    Tracked& t = stations_[v.info.header.station_id];
    bool info_missing = false;
    if (t.session == session && !v.input_session.empty() && v.input_session != session &&
        !sessions_.count(v.input_session)) {
      // The station runs a new session (its DeviceInput says so) whose StationInfo has not
      // come. Seen with Fast DDS 2.9 when a station restarts under the same id: the old run's
      // unregistration can replace the new StationInfo in the keep-last-1 reader. After
      // kStationInfoWait_ns the run is stored with the station's previous StationInfo.
      auto [it, fresh] = awaiting_info_.try_emplace(v.input_session, pass_ns);
      if (pass_ns - it->second < kStationInfoWait_ns) continue;
      session = v.input_session;
      info_missing = true;
      awaiting_info_.erase(it);
    }
    // A session stored already: the current one, or an earlier run whose StationInfo the
    // registry still holds while the new run was stored from its DeviceInput.
    if (t.session == session || sessions_.count(session)) continue;
    if (info_missing) {
      lines.push_back("station " + v.info.header.station_id + ": no StationInfo for session " +
                      session + "; trainee, scene and seed taken from its previous run");
    }
    if (!t.session.empty() && !t.ended) {
      ended.push_back(t.session);
      t.ended = true;
      t.ended_ns = pass_ns;
    }
    if (!t.session.empty()) past_[t.session] = t;
    t = Tracked{};
    t.session = session;
    scores::SessionRow row;
    row.id = session;
    row.course = options_.course;
    row.trainee = v.info.trainee.empty() ? "(unnamed)" : v.info.trainee;
    t.trainee = row.trainee;
    row.scene = FileName(v.info.scene);
    row.scene_path = v.info.scene;
    row.station = v.info.header.station_id;
    row.seed = v.info.seed;
    row.skill = v.info.skill;
    row.device = v.info.device;
    row.instructor_session = console_.session_id();
    // The file being recorded now (a recording started from the page), else --record's.
    row.recording = console_.RecordingPath();
    if (row.recording.empty()) row.recording = options_.recording;
    row.started_ns = v.info.header.stamp_ns ? v.info.header.stamp_ns : RealtimeNowNs();
    if (info_missing) {  // not the previous run's seed, skill and start
      row.seed = 0;
      row.skill = -1;
      row.started_ns = pass_ns;
    }
    if (options_.experiment) {
      const scores::ExperimentDef& e = *options_.experiment;
      auto a = assignment_.find(row.trainee);
      int& done = started_trials_[row.trainee];
      if (a == assignment_.end()) {
        lines.push_back("experiment " + e.name + ": trainee '" + row.trainee + "' of station " +
                        row.station + " is not in the experiment; no cues sent");
      } else if (FileName(e.scene) != row.scene) {
        lines.push_back("experiment " + e.name + ": station " + row.station + " runs " + row.scene +
                        ", not the experiment's " + FileName(e.scene) + "; not counted as a trial");
      } else if (done >= e.trials_per_trainee) {
        lines.push_back("experiment " + e.name + ": trainee '" + row.trainee + "' has done all " +
                        std::to_string(e.trials_per_trainee) + " trials; not counted");
      } else {
        row.experiment = e.name;
        row.condition = a->second;
        row.trial = ++done;
        t.counted = true;
        t.trial = row.trial;
        const scores::CueCondition* condition = nullptr;
        for (const auto& c : e.conditions) {
          if (c.name == a->second) condition = &c;
        }
        // The condition for this run of the station, at least one command (an explicit "no
        // cue" for an empty condition): a station waiting for it (--wait-for-condition)
        // starts the trial with it in force from step 0.
        const std::size_t sent =
            console_.SendCondition(row.station, session, condition->cues).size();
        lines.push_back("experiment " + row.experiment + ": " + row.trainee + " trial " +
                        std::to_string(row.trial) + "/" + std::to_string(e.trials_per_trainee) +
                        ", condition " + row.condition + " (" + std::to_string(sent) +
                        (sent == 1 ? " command" : " commands") + " sent to " + row.station + ")");
      }
    }
    new_sessions.push_back(std::move(row));
  }
  const std::int64_t now = RealtimeNowNs();
  for (const std::string& session : ended) scores::EndSession(*db_, session, now);
  for (const scores::SessionRow& row : new_sessions) {
    scores::AddSession(*db_, row);
    sessions_.insert(row.id);
  }
  // Final scores (every one the console received), then the live ones of the registry.
  std::vector<net::Score> finals;
  finals.swap(pending_finals_);
  finals.insert(finals.end(), final_scores.begin(), final_scores.end());
  for (const net::Score& s : finals) {
    Tracked* t = FindSession(s.header.session_id);
    if (t == nullptr) {
      if (!sessions_.count(s.header.session_id) && pending_finals_.size() < 10'000) {
        pending_finals_.push_back(s);  // its StationInfo has not come yet
      }
      continue;
    }
    SaveScore(s, *t);
  }
  for (const StationView& v : stations) {
    auto it = stations_.find(v.info.header.station_id);
    if (it == stations_.end()) continue;
    Tracked& t = it->second;
    if (v.score.latest && v.score.latest->header.session_id == t.session && !t.score_final) {
      const net::Score& s = *v.score.latest;
      const bool leaving = v.presence != Presence::kAlive;
      if (s.header.step != t.score_step &&
          (leaving || now - t.score_saved_ns >= kLiveScorePeriod_ns)) {
        SaveScore(s, t);
      }
    }
    if (!t.ended && v.presence != Presence::kAlive) {
      t.ended = true;
      t.ended_ns = now;
      scores::EndSession(*db_, t.session, now);
    }
  }
  if (options_.experiment) VoidUnfinishedTrials(now, lines);
  // Events of stored sessions; the others wait for their session's StationInfo.
  std::vector<net::TaskEvent> all;
  all.swap(pending_events_);
  all.insert(all.end(), events.begin(), events.end());
  std::map<std::string, std::vector<scores::EventRow>> by_session;
  for (net::TaskEvent& e : all) {
    if (!sessions_.count(e.header.session_id)) {
      if (pending_events_.size() < 100'000) pending_events_.push_back(std::move(e));
      continue;
    }
    by_session[e.header.session_id].push_back(
        {e.header.step, net::TaskEventKindName(e.kind), e.cue_id, e.value, e.text, now});
  }
  for (const auto& [session, rows] : by_session) scores::AddEvents(*db_, session, rows);
  return lines;
}

void ScoresWriter::Finish(const std::vector<StationView>& stations) {
  for (const StationView& v : stations) {
    auto it = stations_.find(v.info.header.station_id);
    if (it == stations_.end()) continue;
    Tracked& t = it->second;
    if (v.score.latest && v.score.latest->header.session_id == t.session) {
      SaveScore(*v.score.latest, t);
    }
    if (t.ended) continue;
    t.ended = true;
    scores::EndSession(*db_, t.session, RealtimeNowNs());
  }
}

std::vector<scores::ScoredSession> ScoresWriter::FinalScores() {
  std::vector<scores::ScoredSession> out = scores::LoadScoredSessions(*db_, options_.course);
  std::erase_if(out, [](const scores::ScoredSession& s) { return !s.is_final; });
  return out;
}

}  // namespace microdex::instructor
