// The knot-topology module: every knot it shows is one the stitch-knot recogniser names as the
// scene says; a button press (its rising edge) answers the knot shown and brings the next; the
// answers are counted right or wrong with their response times.
#include "station/knot_quiz_module.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "common/knot/stitch_knot.h"

namespace microdex::station {
namespace {

scene::SceneModel QuizScene() {
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  return scene::LoadScene(std::string(root != nullptr ? root : ".") +
                          "/assets/scenes/knot_topology.yaml");
}

TEST(KnotQuizModule, ShowsRecognisedKnotsAndCountsAnswers) {
  const scene::SceneModel scene = QuizScene();
  KnotQuizModule m(scene);
  const auto& items = scene.knots->items;
  for (std::size_t i = 0; i < items.size(); ++i) {
    EXPECT_EQ(knot::RecogniseStitchKnot(m.shape(i)), items[i]) << i;
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
