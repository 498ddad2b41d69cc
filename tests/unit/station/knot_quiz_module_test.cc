// The knot-topology module: every knot it shows is one the stitch-knot recogniser names as the
// scene says; a button press (its rising edge) answers the knot shown and brings the next; the
// answers are counted right or wrong with their response times.
#include "station/knot_quiz_module.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "common/knot/stitch_knot.h"

namespace microdex::station {
namespace {

scene::SceneModel QuizScene() {
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  return scene::LoadScene(std::string(root != nullptr ? root : ".") +
                          "/assets/scenes/knot_topology.yaml");
}

// Every knot shown is one tied by the thread module around a stitch (assets/knots, 193 nodes),
// read with the thread's own diameter (the files' `# thread_diameter_m`, at the shape's
// scale): the square, granny and surgeon's knots and the half hitches from the closure (tied,
// not twisted pairs; a half hitch's closure is a trefoil); the slip knots as two half hitches
// on one straight strand, the post (a square knot capsized: its closure is still the square
// knot); the second item of a class is the mirror image of the first. A tied knot's file
// that is missing is named with the scene's file, line and field.
TEST(KnotQuizModule, ShowsKnotsTiedByTheThreadModule) {
  const scene::SceneModel scene = QuizScene();
  const auto& items = scene.knots->items;
  int tied = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::vector<Eigen::Vector3d> shape = scene.knots->ItemShape(i);
    knot::StitchKnotOptions options;
    options.thread_diameter_m = scene.knots->ItemThreadDiameter(i);
    // 25 um nylon drawn 2.5 to 10 times its size.
    EXPECT_GE(options.thread_diameter_m, 62.5e-6 - 1e-12) << i;
    EXPECT_LE(options.thread_diameter_m, 250e-6 + 1e-12) << i;
    const knot::StitchKnotAnalysis a = knot::AnalyzeStitchKnot(shape, options);
    EXPECT_EQ(a.type, items[i]) << i;
    if (items[i] == knot::StitchKnotType::kSlip) {
      EXPECT_EQ(a.closure, knot::KnotType::kSquare) << i;
      ASSERT_EQ(a.throws.size(), 2u) << i;
      EXPECT_TRUE(a.throws[0].hitch && a.throws[1].hitch) << i;
      EXPECT_EQ(a.throws[0].post_strand, a.throws[1].post_strand) << i;
      EXPECT_EQ(a.throws[0].hand, -a.throws[1].hand) << i << ": a lark's head, opposite senses";
    }
    EXPECT_TRUE(a.from_closure) << i;
    ++tied;
  }
  EXPECT_EQ(tied, 10);
  const std::vector<Eigen::Vector3d> first = scene.knots->ItemShape(0);   // square
  const std::vector<Eigen::Vector3d> second = scene.knots->ItemShape(6);  // square again
  ASSERT_EQ(first.size(), second.size());
  EXPECT_DOUBLE_EQ(second[5].x(), -first[5].x());
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  const std::string path =
      std::string(root != nullptr ? root : ".") + "/assets/scenes/knot_topology.yaml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  // The scene with the tied file `from` replaced by `to` is refused, its error naming `key`
  // and containing `names`.
  const auto expect_refused = [&](const std::string& from, const std::string& to,
                                  const std::string& key, const std::string& names) {
    std::string changed = text.str();
    changed.replace(changed.find(from), from.size(), to);
    try {
      (void)scene::ParseScene(changed, path);
      ADD_FAILURE() << to << " accepted for " << key;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  expect_refused("../knots/tied_granny.obj", "../knots/missing.obj", "knots.tied.granny",
                 "missing.obj");
  // A tied knot of another class than its key: refused when the scene is loaded, naming the
  // key and the file (the scene's loader checks every shape shown; the module does not again).
  expect_refused("../knots/tied_square.obj", "../knots/tied_granny.obj", "knots.tied.square",
                 "tied_granny.obj: recognised as granny");
  // A tied knot whose thread diameter is malformed: named with its file and line.
  const std::filesystem::path bad_obj =
      std::filesystem::temp_directory_path() / "microdex_quiz_bad_diameter.obj";
  {
    std::ifstream granny(std::string(root != nullptr ? root : ".") +
                         "/assets/knots/tied_granny.obj");
    std::stringstream g;
    g << granny.rdbuf();
    std::string obj = g.str();
    obj.replace(obj.find("# thread_diameter_m 2.5e-05"), 27, "# thread_diameter_m -2.5e-05");
    std::ofstream(bad_obj) << obj;
  }
  expect_refused("../knots/tied_granny.obj", bad_obj.string(), "knots.tied.granny",
                 "microdex_quiz_bad_diameter.obj:3: malformed");
}

TEST(KnotQuizModule, ShowsRecognisedKnotsAndCountsAnswers) {
  const scene::SceneModel scene = QuizScene();
  KnotQuizModule m(scene);
  const auto& items = scene.knots->items;
  for (std::size_t i = 0; i < items.size(); ++i) {
    knot::StitchKnotOptions options;
    options.thread_diameter_m = scene.knots->ItemThreadDiameter(i);
    EXPECT_EQ(knot::RecogniseStitchKnot(m.shape(i), options), items[i]) << i;
  }
  state::StationState s;
  m.InitState(s);
  ToolInput in;
  in.dt_s = 1e-3;
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  const auto step = [&](std::uint64_t k, std::uint32_t buttons) {
    in.step = k;
    s.tool.buttons = buttons;
    m.Step(in, s, f);
  };
  // Item 0 answered right at 2 s (held for three steps: one answer), item 1 wrong at 3.5 s.
  step(1000, 0);
  step(2000, static_cast<std::uint32_t>(items[0]));
  step(2001, static_cast<std::uint32_t>(items[0]));
  step(2002, static_cast<std::uint32_t>(items[0]));
  step(2003, 0);
  EXPECT_EQ(s.knots->item, 1);
  EXPECT_EQ(s.knots->correct, 1);
  const auto wrong = items[1] == knot::StitchKnotType::kSquare ? knot::StitchKnotType::kGranny
                                                               : knot::StitchKnotType::kSquare;
  step(3500, static_cast<std::uint32_t>(wrong));
  EXPECT_EQ(s.knots->item, 2);
  EXPECT_EQ(s.knots->correct, 1);
  EXPECT_EQ(s.knots->last_answer, static_cast<std::int32_t>(wrong));
  EXPECT_NEAR(s.knots->response_time_sum_s, 2.0 + 1.5, 1e-12);
  EXPECT_EQ(f, Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace microdex::station
