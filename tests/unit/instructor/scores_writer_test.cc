// ScoresWriter (instructor/scores_writer.h) on registry snapshots made by hand: a trial per
// station run, a run seen only through its DeviceInput stored after its StationInfo failed to
// come, and a trial that ends without a final score made void and repeated.

#include "instructor/scores_writer.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "common/net/dds_context.h"
#include "common/scores/scores_store.h"

namespace microdex::instructor {
namespace {

using namespace std::chrono_literals;

constexpr int kDomain = 142;

StationView View(const std::string& station, const std::string& session,
                 const std::string& trainee) {
  StationView v;
  v.info.header = {station, session, 0, 1'000};
  v.info.trainee = trainee;
  v.info.scene = "/somewhere/hold.yaml";
  v.info.seed = 9;
  v.info.skill = 0.5;
  v.info.device = "sim";
  v.input_session = session;
  return v;
}

net::Score Final(const std::string& station, const std::string& session, double score) {
  net::Score s;
  s.header = {station, session, 1499, 2'000};
  s.is_final = true;
  s.score = score;
  s.task = "tremor_hold";
  return s;
}

bool Has(const std::vector<std::string>& lines, const std::string& text) {
  for (const auto& l : lines) {
    if (l.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(ScoresWriter, TrialsFallbackAndVoidTrials) {
  std::string dir = "/tmp/microdex-writer-XXXXXX";
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  InstructorOptions io;
  io.dds.profile_file = net::DefaultDdsProfileFile();
  io.dds.domain_id = kDomain;
  io.dds.participant_name = "scores-writer-test";
  Instructor console(io);
  ScoresWriterOptions o;
  o.url = dir + "/course.db";
  o.course = "c";
  o.experiment = scores::ParseExperiment(
      "name: e\nscene: hold.yaml\nseed: 3\ntrials_per_trainee: 2\nconditions:\n  none: []\n"
      "  audio: [audio_click:0.8]\ntrainees: [ana, ben]\n",
      "e.yaml");
  ScoresWriter w(o, console);
  ASSERT_EQ(w.assignment().size(), 2u);

  // Trial 1 of ana: stored, its cues sent, its final score counted.
  StationView ana = View("st-a", "a-1", "ana");
  auto lines = w.Update({ana}, {}, {});
  EXPECT_TRUE(Has(lines, "ana trial 1/2, condition " + w.assignment().at("ana"))) << lines.at(0);
  w.Update({ana}, {}, {Final("st-a", "a-1", 40)});

  // Ana's next run: its DeviceInput arrives, its StationInfo does not. Stored after 1 s as
  // trial 2, from the previous StationInfo.
  ana.input_session = "a-2";
  lines = w.Update({ana}, {}, {});
  EXPECT_FALSE(Has(lines, "trial 2")) << "stored before its StationInfo had a chance";
  std::this_thread::sleep_for(1100ms);
  lines = w.Update({ana}, {}, {});
  EXPECT_TRUE(Has(lines, "no StationInfo for session a-2"));
  EXPECT_TRUE(Has(lines, "ana trial 2/2"));
  // The old StationInfo is still in the registry: not taken for yet another run.
  lines = w.Update({ana}, {}, {});
  EXPECT_TRUE(lines.empty()) << lines.at(0);

  // Trial 2 ends without a final score (the station is lost): void after 3 s, and the next
  // run repeats trial 2.
  ana.presence = Presence::kLost;
  w.Update({ana}, {}, {});
  std::this_thread::sleep_for(3100ms);
  lines = w.Update({ana}, {}, {});
  EXPECT_TRUE(Has(lines, "ana trial 2 void (session a-2")) << (lines.empty() ? "" : lines[0]);
  EXPECT_FALSE(w.ExperimentDone());
  ana = View("st-a", "a-3", "ana");
  lines = w.Update({ana}, {}, {});
  EXPECT_TRUE(Has(lines, "ana trial 2/2"));
  w.Update({ana}, {}, {Final("st-a", "a-3", 60)});

  // Ben's two trials, then the experiment is done.
  StationView ben = View("st-b", "b-1", "ben");
  w.Update({ana, ben}, {}, {Final("st-b", "b-1", 30)});
  ben = View("st-b", "b-2", "ben");
  w.Update({ana, ben}, {}, {});
  EXPECT_FALSE(w.ExperimentDone());
  w.Update({ana, ben}, {}, {Final("st-b", "b-2", 35)});
  EXPECT_TRUE(w.ExperimentDone());

  // A trainee outside the experiment: stored, not counted, said so.
  lines = w.Update({ana, ben, View("st-c", "c-1", "carl")}, {}, {});
  EXPECT_TRUE(Has(lines, "'carl' of station st-c is not in the experiment"));

  const auto db = scores::ScoresDb::Open(o.url);
  const auto rows = db->Query(
      "SELECT s.id, s.trial, s.seed, c.is_final FROM sessions s LEFT JOIN scores c ON c.session "
      "= s.id WHERE s.trainee = 'ana' ORDER BY s.id");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].Int(1), 1);
  EXPECT_TRUE(rows[1].IsNull(1));  // a-2: void
  EXPECT_EQ(rows[1].Int(2), 0);    // its seed unknown
  EXPECT_EQ(rows[2].Int(1), 2);
  EXPECT_EQ(rows[2].Int(3), 1);
  EXPECT_EQ(scores::CountTrials(*db, "e", "ana"), 2);
}

}  // namespace
}  // namespace microdex::instructor
