// Learning curves from a scores database: one PNG per trainee, with the data it shows.

#include <gtest/gtest.h>
#include <stdlib.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/scores/scores_db.h"
#include "common/scores/scores_store.h"
#include "instructor/scores_report.h"

namespace microdex::instructor {
namespace {

std::string Read(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(LearningCurves, OnePngPerTraineeWithEachSceneAsALine) {
  std::string dir = "/tmp/microdex-curves-XXXXXX";
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  const auto db = scores::ScoresDb::Open(dir + "/course.db");
  int n = 0;
  const std::vector<std::string> trainees = {"ana", "ben"};
  const std::vector<std::string> ids = {"0", "1", "2", "3"};
  for (const std::string& trainee : trainees) {
    for (int k = 0; k < 4; ++k) {
      scores::SessionRow s;
      s.id = trainee + "-" + ids[static_cast<std::size_t>(k)];
      s.course = std::string(1, 'c');
      s.trainee = trainee;
      s.scene = k % 2 ? "grasp.yaml" : "tremor_hold.yaml";
      s.scene_path = s.scene;
      s.station = "st";
      s.device = "sim";
      s.started_ns = ++n;
      scores::AddSession(*db, s);
      scores::ScoreRow r;
      r.is_final = true;
      r.score = 20 + 15 * k;
      scores::SaveScore(*db, s.id, r);
    }
  }
  const auto files = WriteLearningCurves(*db, "c", dir + "/curves");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0], dir + "/curves/curve_ana.png");
  for (const auto& f : files) {
    const std::string png = Read(f);
    ASSERT_GT(png.size(), 1000u) << f;
    EXPECT_EQ(png.substr(1, 3), "PNG") << f;
  }
  // The data: ana's sessions 1 and 3 in tremor_hold, 2 and 4 in grasp, with their scores.
  const std::string dat = Read(dir + "/curves/curve_ana.dat");
  EXPECT_NE(dat.find("# grasp.yaml\n2 35\n4 65\n"), std::string::npos) << dat;
  EXPECT_NE(dat.find("# tremor_hold.yaml\n1 20\n3 50\n"), std::string::npos) << dat;
  // No session in that course: a clear error.
  try {
    WriteLearningCurves(*db, "other", dir + "/none");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no scored session in course 'other'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace microdex::instructor
