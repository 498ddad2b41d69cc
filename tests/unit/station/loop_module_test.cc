// The loop-along-a-wire module: its clearance is the geometry's exact query, touching pushes
// the loop off the wire and is a fault, the progress runs from the course's start to its end,
// and the convergent guidance field pulls the loop towards the wire's axis.
#include "station/loop_module.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "station/scene_run.h"
#include "station/station_step.h"

namespace microdex::station {
namespace {

scene::SceneModel LoopScene() {
  const char* root = std::getenv("MICRODEX_SOURCE_DIR");
  return scene::LoadScene(std::string(root != nullptr ? root : ".") +
                          "/assets/scenes/loop_along_wire.yaml");
}

TEST(LoopModule, ClearanceForceAndFault) {
  const scene::SceneModel scene = LoopScene();
  LoopModule m(scene);
  state::StationState s;
  m.InitState(s);
  ToolInput in;
  // Centred on the course's start, the loop across the wire: no contact, clearance R − r_l − r_w.
  in.X_WT = scene.CalcIdealToolPose(0);
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  m.Step(in, s, f);
  const double margin =
      scene.loop->loop.radius_m - scene.loop->loop.wire_radius_m - scene.loop->wire.radius_m;
  EXPECT_NEAR(s.loop->clearance.clearance_m, margin, 1e-12);
  EXPECT_FALSE(m.Status(s).fault);
  EXPECT_EQ(f, Eigen::Vector3d::Zero());
  EXPECT_NEAR(s.loop->offset_m, 0, 1e-12);
  // Shifted sideways past the margin: contact, a fault, and a force pushing the loop back so
  // the wire is centred again (towards −shift).
  const Eigen::Vector3d shift = in.X_WT.linear().col(1) * (margin + 0.1e-3);
  in.X_WT.translation() += shift;
  m.Step(in, s, f);
  EXPECT_TRUE(s.loop->clearance.contact);
  EXPECT_TRUE(m.Status(s).fault);
  EXPECT_NEAR(s.loop->clearance.clearance_m, -0.1e-3, 1e-9);
  EXPECT_LT(f.dot(shift), 0);
  EXPECT_NEAR(f.norm(), scene.loop->wall_stiffness_N_per_m * 0.1e-3, 1e-9);
  EXPECT_NEAR(s.loop->offset_m, shift.norm(), 1e-9);
}

// The convergent field (a cue) pulls a novice's loop towards the wire: the mean offset falls.
TEST(LoopModule, ConvergentFieldPullsTowardsTheWire) {
  scene::SceneModel scene = LoopScene();
  SimTraineeDef def;
  def.skill = 0.2;
  const double plain = RunSceneWithTrainee(scene, def, 1).score.deviation_mean_m;
  scene.cues.on.emplace_back(cues::CueKind::kConvergentField, 1500);
  const double guided = RunSceneWithTrainee(scene, def, 1).score.deviation_mean_m;
  EXPECT_LT(guided, 0.8 * plain) << "plain " << plain << " guided " << guided;
}

}  // namespace
}  // namespace microdex::station
