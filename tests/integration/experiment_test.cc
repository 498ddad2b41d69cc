// A cue experiment end to end (instructor/README.md "Cue experiments"): microdex-instructor
// --experiment assigns nine simulated trainees to three conditions (none, audio, divergent),
// sends each trial's cues, records the session and writes the scores database; the stations
// are microdex-station processes with the simulated trainee. The trainee learns between
// trials at a rate that depends on the cues its station actually applied (read from the
// station's --score-out, not from the assignment): fast when it heard the audio clicks, slowly
// otherwise. microdex-replay --db ... --experiment must then find `audio` the best condition,
// with a positive effect size against `none` whose 95 % confidence interval excludes zero.
// Each station waits for its trial's condition (--wait-for-condition), so every trial starts
// with it: the acknowledgements all name step 0. No trial is void, not even in a round run
// while busy threads load the machine.

#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/record/recorded_topics.h"
#include "common/record/session_reader.h"
#include "common/scores/scores_db.h"
#include "common/scores/scores_store.h"
#include "cue_overlayPubSubTypes.h"
#include "instructor/recorded_sample.h"
#include "instructor/scores_report.h"
#include "tests/integration/process.h"
#include "tests/support/postgres_server.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
using testing::KillAll;
using testing::ReadFile;
using testing::Spawn;
using testing::WaitExit;

constexpr int kDomain = 141;
constexpr int kTrainees = 9;
constexpr int kTrials = 4;
// Learning per trial: skill → 1 − (1 − skill) e^(−rate).
constexpr double kRateWithAudio = 0.5;
constexpr double kRateOtherwise = 0.1;

// A short hold (1.5 s, 3 s limit) of the tremor_hold task.
constexpr const char* kScene = R"(name: hold-short
modules: [tremor]
task:
  kind: tremor_hold
  target_m: [0, 0, 0.002]
  hold_s: 1.5
  time_limit_s: 3
  tolerance_m: 0.2e-3
scoring:
  tremor_rms_m: {weight: 2, limit: 80.0e-6}
  drift_m: {weight: 2, limit: 400.0e-6}
  outside_fraction: {weight: 1, limit: 1.0}
microscope:
  magnification: 20
  look_at_m: [0, 0, 0.002]
  view_dir: [0, 0, -1]
haptic:
  rate_hz: 1000
  max_force_N: 2.0
)";

std::string TmpDir() {
  std::string dir = "/tmp/microdex-experiment-XXXXXX";
  return mkdtemp(dir.data()) ? dir : "/tmp";
}

std::string Trainee(int i) { return "trainee" + std::to_string(i + 1); }

class ExperimentTest : public ::testing::Test {
 protected:
  void TearDown() override { KillAll(pids_); }
  std::string dir_ = TmpDir();
  std::vector<pid_t> pids_;
};

TEST_F(ExperimentTest, TheReportRecoversTheConditionThatHelpsLearning) {
  std::ofstream(dir_ + "/hold_short.yaml") << kScene;
  std::string trainees;
  for (int i = 0; i < kTrainees; ++i) trainees += (i ? ", " : "") + Trainee(i);
  const std::string experiment = dir_ + "/experiment.yaml";
  std::ofstream(experiment) << "name: audio-pilot\nscene: hold_short.yaml\nseed: 11\n"
                            << "trials_per_trainee: " << kTrials << "\n"
                            << "conditions:\n  none: []\n  audio: [audio_click:0.8]\n"
                            << "  divergent: [divergent:100, visual_path]\n"
                            << "trainees: [" << trainees << "]\n";
  const std::string db_file = dir_ + "/course.db";
  const pid_t console =
      Spawn("microdex-instructor",
            {"--headless", "--table-period", "0", "--domain", std::to_string(kDomain), "--db",
             db_file, "--course", "pilot", "--experiment", experiment, "--record",
             dir_ + "/session.db", "--duration", "100"},
            dir_ + "/instructor.log");
  pids_.push_back(console);

  // Each round, the trainees in `who` do one trial each (all stations at once, paced at
  // 1 kHz); the simulated trainees then learn from what their station applied.
  std::vector<double> skill(kTrainees);
  for (int i = 0; i < kTrainees; ++i) skill[static_cast<std::size_t>(i)] = 0.10 + 0.02 * i;
  std::map<std::string, int> heard_audio, runs;  // trainee → runs with the audio cue, runs
  int round = 0, acks = 0;
  const auto run_round = [&](const std::vector<int>& who, int busy_threads) {
    ++round;
    // Artificial load: busy threads for the whole round (the machine's cores and more).
    std::atomic<bool> busy_stop{false};
    std::vector<std::thread> busy;
    for (int k = 0; k < busy_threads; ++k) {
      busy.emplace_back([&busy_stop] {
        volatile double x = 1;
        while (!busy_stop.load(std::memory_order_relaxed)) x = x * 1.0000001 + 1e-9;
      });
    }
    struct JoinBusy {
      std::atomic<bool>& stop;
      std::vector<std::thread>& threads;
      ~JoinBusy() {
        stop = true;
        for (auto& t : threads) t.join();
      }
    } join_busy{busy_stop, busy};
    std::vector<pid_t> stations;
    for (int i : who) {
      const std::string id = Trainee(i);
      char s[32];
      std::snprintf(s, sizeof s, "%.6f", skill[static_cast<std::size_t>(i)]);
      stations.push_back(Spawn(
          "microdex-station",
          {"--scene", dir_ + "/hold_short.yaml", "--station-id", id, "--trainee", id, "--seed",
           std::to_string(100 * round + i), "--skill", s, "--no-realtime", "--domain",
           std::to_string(kDomain), "--wait-for-recorder", "20", "--wait-for-condition", "20",
           "--score-out", dir_ + "/" + id + "_" + std::to_string(round) + ".json"},
          dir_ + "/" + id + ".log"));
      pids_.push_back(stations.back());
    }
    for (std::size_t k = 0; k < stations.size(); ++k) {
      const auto status = WaitExit(stations[k], 60s);
      ASSERT_TRUE(status.has_value()) << Trainee(who[k]);
      ASSERT_EQ(*status, 0) << ReadFile(dir_ + "/" + Trainee(who[k]) + ".log");
    }
    for (int i : who) {
      const std::string json =
          ReadFile(dir_ + "/" + Trainee(i) + "_" + std::to_string(round) + ".json");
      const auto at = json.find("\"cues_applied\"");
      ASSERT_NE(at, std::string::npos) << json;
      const std::string applied = json.substr(at, json.find(']', at) - at);
      const bool audio = applied.find("\"audio_click\"") != std::string::npos;
      // Every cue of the trial's condition (at least one: "clear" for none) applied at step 0.
      std::size_t acked = 0;
      for (std::size_t k = applied.find("\"step\": "); k != std::string::npos;
           k = applied.find("\"step\": ", k + 1)) {
        EXPECT_EQ(applied.substr(k + 8, 2), "0}")
            << Trainee(i) << " round " << round << ": " << applied;
        ++acked;
      }
      EXPECT_GE(acked, 1u) << Trainee(i) << " round " << round << ": " << applied;
      acks += static_cast<int>(acked);
      heard_audio[Trainee(i)] += audio ? 1 : 0;
      ++runs[Trainee(i)];
      double& s = skill[static_cast<std::size_t>(i)];
      s = 1 - (1 - s) * std::exp(-(audio ? kRateWithAudio : kRateOtherwise));
    }
  };
  std::vector<int> everyone(kTrainees);
  for (int i = 0; i < kTrainees; ++i) everyone[static_cast<std::size_t>(i)] = i;
  for (int trial = 1; trial <= kTrials; ++trial) {
    // The second round under artificial load: two busy threads on the 2-core machine.
    run_round(everyone, trial == 2 ? 2 : 0);
    if (HasFatalFailure()) return;
  }
  // Every trial scored: the instructor ends the experiment by itself. A run the instructor
  // did not count (its StationInfo never arrived: see the README) is run again, as an
  // operator would, for the trainees the database shows short of trials.
  std::optional<int> console_status = WaitExit(console, 5s);
  int reruns = 0;
  for (int extra = 0; extra < 2 && !console_status; ++extra) {
    std::vector<int> short_of_trials;
    {
      const auto db = scores::ScoresDb::Open(db_file);
      for (int i = 0; i < kTrainees; ++i) {
        const auto n = db->Query(
            "SELECT COUNT(*) FROM sessions s JOIN scores c ON c.session = s.id WHERE "
            "s.experiment = 'audio-pilot' AND s.trainee = ? AND c.is_final = 1 AND s.trial IS NOT "
            "NULL",
            {Trainee(i)});
        if (n.at(0).Int(0) < kTrials) short_of_trials.push_back(i);
      }
    }
    reruns += static_cast<int>(short_of_trials.size());
    if (!short_of_trials.empty()) run_round(short_of_trials, 0);
    if (HasFatalFailure()) return;
    console_status = WaitExit(console, 10s);
  }
  std::printf("runs not counted by the instructor and run again: %d of %d\n", reruns,
              kTrainees * kTrials + reruns);
  // No trial void: the instructor saw every run's StationInfo and final score.
  EXPECT_EQ(reruns, 0);
  EXPECT_EQ(ReadFile(dir_ + "/instructor.log").find(" void "), std::string::npos)
      << ReadFile(dir_ + "/instructor.log");
  ASSERT_TRUE(console_status.has_value()) << ReadFile(dir_ + "/instructor.log");
  ASSERT_EQ(*console_status, 0) << ReadFile(dir_ + "/instructor.log");
  EXPECT_NE(ReadFile(dir_ + "/instructor.log").find("every trial scored"), std::string::npos);

  // The database: a balanced assignment, every trial of every trainee tagged and scored, the
  // audio trainees (and only they) heard the clicks in every trial.
  const auto db = scores::ScoresDb::Open(db_file);
  const scores::ExperimentRow e = scores::LoadExperiment(*db, "audio-pilot");
  ASSERT_EQ(e.assignments.size(), static_cast<std::size_t>(kTrainees));
  std::map<std::string, int> per_condition;
  for (const auto& [trainee, condition] : e.assignments) {
    ++per_condition[condition];
    EXPECT_EQ(heard_audio[trainee], condition == "audio" ? runs[trainee] : 0) << trainee;
  }
  EXPECT_EQ(per_condition,
            (std::map<std::string, int>{{"audio", 3}, {"divergent", 3}, {"none", 3}}));
  // Every trainee's trials 1..T, each with a final score (void runs, trial NULL, aside).
  std::map<std::string, std::set<int>> trials;
  for (const auto& s : scores::LoadScoredSessions(*db, "pilot", "audio-pilot")) {
    if (s.trial == 0) continue;
    EXPECT_TRUE(s.is_final) << s.id;
    EXPECT_TRUE(trials[s.trainee].insert(s.trial).second) << s.id << " trial " << s.trial;
  }
  ASSERT_EQ(trials.size(), static_cast<std::size_t>(kTrainees));
  for (const auto& [trainee, t] : trials) {
    EXPECT_EQ(t, (std::set<int>{1, 2, 3, 4})) << trainee;
  }
  // The cue-applied events in the database: every trial's condition acknowledged at step 0
  // (the station held its first step until it had the condition, --wait-for-condition), all of
  // it (the audio and divergent conditions' cues; `none`: one explicit clear), and nothing
  // else. The stations wait for every writer's reader before they start (--wait-for-recorder),
  // so each acknowledgement reaches the instructor.
  const auto applied = db->Query(
      "SELECT s.id, s.condition, COUNT(e.step), MIN(e.step), MAX(e.step), "
      "SUM(e.text = 'clear'), SUM(e.text = 'audio_click'), SUM(e.text = 'divergent'), "
      "SUM(e.text = 'visual_path') FROM sessions s LEFT JOIN events e ON e.session = s.id AND "
      "e.kind = 'cue-applied' WHERE s.experiment = 'audio-pilot' AND s.trial IS NOT NULL GROUP "
      "BY s.id, s.condition");
  ASSERT_EQ(applied.size(), static_cast<std::size_t>(kTrainees * kTrials));
  const std::map<std::string, std::vector<std::int64_t>> expected = {
      {"none", {1, 1, 0, 0, 0}}, {"audio", {1, 0, 1, 0, 0}}, {"divergent", {2, 0, 0, 1, 1}}};
  for (const auto& row : applied) {
    const std::vector<std::int64_t>& want = expected.at(row.Text(1));
    EXPECT_EQ(row.Int(2), want[0]) << row.Text(0) << " " << row.Text(1);
    if (row.Int(2) == 0) continue;
    EXPECT_EQ(row.Int(3), 0) << row.Text(0) << ": the condition's first cue after step 0";
    EXPECT_EQ(row.Int(4), 0) << row.Text(0) << ": the condition's last cue after step 0";
    for (int k = 1; k < 5; ++k) EXPECT_EQ(row.Int(4 + k), want[k]) << row.Text(0) << " " << k;
  }
  std::printf("trials: %zu, every condition acknowledged at step 0 (%d acknowledgements)\n",
              applied.size(), acks);

  // The recording holds every station's cue overlays; those with a drawn path come from the
  // divergent trainees' stations only (their condition's visual_path).
  {
    record::SessionReader rec(dir_ + "/session.db");
    std::map<std::string, int> overlays, drawn;
    rec.ForEach({static_cast<int>(record::TopicIndex::kCueOverlay)},
                [&](const record::MessageView& m) {
                  msg::CueOverlay o;
                  EXPECT_TRUE(instructor::DecodeSample<msg::CueOverlayPubSubType>(m.cdr, o));
                  ++overlays[std::string(m.station)];
                  if (!o.polylines().empty()) ++drawn[std::string(m.station)];
                  return true;
                });
    EXPECT_TRUE(rec.problems().empty());
    EXPECT_EQ(overlays.size(), static_cast<std::size_t>(kTrainees));
    ASSERT_EQ(drawn.size(), 3u);
    for (const auto& [station, n] : drawn) {
      EXPECT_GT(n, 10) << station;
      for (const auto& [trainee, condition] : e.assignments) {
        if (trainee == station) {
          EXPECT_EQ(condition, "divergent") << station;
        }
      }
    }
  }

  // The report, through the command line (PNG, Markdown) and in-process (the figures).
  const std::string report = dir_ + "/report";
  const pid_t replay =
      Spawn("microdex-replay", {"--db", db_file, "--experiment", experiment, "--report", report},
            dir_ + "/report.log");
  pids_.push_back(replay);
  const auto replay_status = WaitExit(replay, 60s);
  ASSERT_TRUE(replay_status.has_value());
  ASSERT_EQ(*replay_status, 0) << ReadFile(dir_ + "/report.log");
  const std::string png = ReadFile(report + "/experiment_audio-pilot.png");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  const std::string md = ReadFile(report + "/experiment_audio-pilot.md");
  EXPECT_NE(md.find("Best condition: audio"), std::string::npos) << md;

  const auto r = instructor::WriteExperimentReport(*db, "audio-pilot", dir_ + "/report2");
  EXPECT_EQ(r.best, "audio") << md;
  bool found = false;
  for (const auto& k : r.contrasts) {
    if (k.a == "none" && k.b == "audio") {
      found = true;
      EXPECT_LT(k.effect.hi, 0) << "none against audio: g " << k.effect.g << " [" << k.effect.lo
                                << ", " << k.effect.hi << "]\n"
                                << md;
    }
  }
  EXPECT_TRUE(found);
  std::printf("%s\n", md.c_str());
}

}  // namespace
}  // namespace microdex

namespace microdex {
namespace {

// Runs a binary to its exit; returns its status, its output in `out`.
int RunTool(const std::string& binary, const std::vector<std::string>& args, const std::string& log,
            std::string* out) {
  const pid_t pid = testing::Spawn(binary, args, log);
  const auto status = testing::WaitExit(pid, std::chrono::seconds(30));
  if (!status) testing::KillAll({pid});
  *out = testing::ReadFile(log);
  return status.value_or(-1);
}

TEST(ExperimentBadInput, MalformedFileAndUnreachableServerAreNamed) {
  const std::string dir = TmpDir();
  const std::string bad = dir + "/bad.yaml";
  std::ofstream(bad) << "name: pilot\nscene: hold.yaml\ntrials_per_trainee: 2\nconditions:\n"
                     << "  none: []\n  audio: [audio_click:7]\ntrainees: [a, b]\n";
  std::string out;
  EXPECT_EQ(RunTool("microdex-instructor",
                    {"--headless", "--domain", std::to_string(kDomain), "--db", dir + "/c.db",
                     "--experiment", bad},
                    dir + "/bad.log", &out),
            2);
  EXPECT_NE(out.find(bad + ":6: conditions.audio: 'audio_click:7'"), std::string::npos) << out;
  // --experiment without --db.
  EXPECT_EQ(
      RunTool("microdex-instructor", {"--headless", "--experiment", bad}, dir + "/nodb.log", &out),
      2);
  EXPECT_NE(out.find("--experiment: needs --db"), std::string::npos) << out;
  // Nothing listens on port 1: the URL (password hidden) and the reason, exit 2.
  const std::string url = "postgresql://trainer:hunter2@127.0.0.1:1/scores";
  EXPECT_EQ(
      RunTool("microdex-instructor",
              {"--headless", "--domain", std::to_string(kDomain), "--duration", "1", "--db", url},
              dir + "/pg.log", &out),
      2);
  EXPECT_NE(out.find("postgresql://trainer:***@127.0.0.1:1/scores: cannot connect: "),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("hunter2"), std::string::npos) << out;
  EXPECT_EQ(RunTool("microdex-replay", {"--db", url, "--curves", dir + "/curves"},
                    dir + "/pg_replay.log", &out),
            2);
  EXPECT_NE(out.find("cannot connect"), std::string::npos) << out;
}

}  // namespace
}  // namespace microdex

namespace microdex {
namespace {

// --wait-for-condition without a condition: exit 2 with one line naming the station (and its
// session) and the instructor it waited for: none at all, or one that sent nothing.
TEST(ExperimentBadInput, StationWithoutItsConditionNamesTheInstructorItWaitedFor) {
  constexpr int kConditionDomain = 145;
  const std::string dir = TmpDir();
  std::ofstream(dir + "/hold_short.yaml") << kScene;
  const std::vector<std::string> station = {"--scene",
                                            dir + "/hold_short.yaml",
                                            "--station-id",
                                            "lonely",
                                            "--no-realtime",
                                            "--duration",
                                            "1",
                                            "--domain",
                                            std::to_string(kConditionDomain),
                                            "--wait-for-condition",
                                            "2"};
  std::string out;
  EXPECT_EQ(RunTool("microdex-station", station, dir + "/alone.log", &out), 2) << out;
  EXPECT_NE(out.find("microdex-station: station 'lonely' (session lonely-"), std::string::npos)
      << out;
  EXPECT_NE(out.find("--wait-for-condition 2: no condition for this run within 2 s from an "
                     "instructor: none found on DDS domain 145"),
            std::string::npos)
      << out;
  // An instructor that runs no experiment: its cue writer matched, it sent nothing.
  const pid_t console = testing::Spawn("microdex-instructor",
                                       {"--headless", "--table-period", "0", "--domain",
                                        std::to_string(kConditionDomain), "--duration", "20"},
                                       dir + "/instructor.log");
  EXPECT_EQ(RunTool("microdex-station", station, dir + "/plain.log", &out), 2) << out;
  EXPECT_NE(out.find("station 'lonely'"), std::string::npos) << out;
  EXPECT_NE(out.find("from the instructor whose cue writer matched on DDS domain 145 (it sent no "
                     "command"),
            std::string::npos)
      << out;
  testing::KillAll({console});
}

// The instructor writing a station run into a PostgreSQL database (a real server, started
// here), read back: the same rows as with SQLite.
class InstructorPostgres : public testing::PostgresServerTest {};

TEST_F(InstructorPostgres, AStationRunIsStoredWithItsFinalScoreAndEvents) {
  const std::string work = TmpDir();
  std::ofstream(work + "/hold_short.yaml") << kScene;
  const std::string url = NewDatabase("course");
  const pid_t console =
      Spawn("microdex-instructor",
            {"--headless", "--table-period", "0", "--domain", std::to_string(kDomain), "--db", url,
             "--course", "pg-course", "--duration", "30"},
            work + "/instructor.log");
  const pid_t station = Spawn(
      "microdex-station",
      {"--scene", work + "/hold_short.yaml", "--station-id", "pg1", "--trainee", "zoe", "--seed",
       "5", "--skill", "0.6", "--no-realtime", "--domain", std::to_string(kDomain),
       "--wait-for-recorder", "20", "--cue", "audio_click:0.5", "--score-out", work + "/pg1.json"},
      work + "/pg1.log");
  const auto station_status = WaitExit(station, 60s);
  ASSERT_TRUE(station_status.has_value());
  ASSERT_EQ(*station_status, 0) << ReadFile(work + "/pg1.log");
  const auto db = scores::ScoresDb::Open(url);
  ASSERT_TRUE(db->is_postgresql());
  // The final score reaches the database within a few seconds of the station's end.
  std::vector<scores::ScoredSession> scored;
  ASSERT_TRUE(testing::WaitUntil(
      [&] {
        scored = scores::LoadScoredSessions(*db, "pg-course");
        return scored.size() == 1 && scored[0].is_final;
      },
      10s))
      << ReadFile(work + "/instructor.log");
  kill(console, SIGINT);
  const auto console_status = WaitExit(console, 20s);
  ASSERT_TRUE(console_status.has_value());
  EXPECT_EQ(*console_status, 0) << ReadFile(work + "/instructor.log");
  EXPECT_EQ(scored[0].trainee, "zoe");
  EXPECT_EQ(scored[0].scene, "hold_short.yaml");
  EXPECT_NEAR(scored[0].score, testing::JsonNumber(ReadFile(work + "/pg1.json"), "score"), 1e-6);
  const auto session =
      db->Query("SELECT seed, skill, ended_ns FROM sessions WHERE id = ?", {scored[0].id});
  ASSERT_EQ(session.size(), 1u);
  EXPECT_EQ(session[0].Int(0), 5);
  EXPECT_DOUBLE_EQ(session[0].Real(1), 0.6);
  EXPECT_FALSE(session[0].IsNull(2));
  const auto terms =
      db->Query("SELECT COUNT(*) FROM score_terms WHERE session = ?", {scored[0].id});
  EXPECT_EQ(terms.at(0).Int(0), 3);  // the scene's three scoring terms
  const auto ends = db->Query("SELECT COUNT(*) FROM events WHERE session = ? AND kind = 'task-end'",
                              {scored[0].id});
  EXPECT_EQ(ends.at(0).Int(0), 1);
}

}  // namespace
}  // namespace microdex
