// The scene loader: the shipped needle-in-tube scene loads; bad files are refused with the
// file and field named; the ideal path keeps the needle inside the tube.
#include "common/scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "common/geometry/arc_torus_sampled.h"

namespace microdex::scene {
namespace {

const char* kGood = R"(
name: t
modules: [needle, tremor]
vessel: {core_radius_m: 5.0e-3, tube_radius_m: 0.5e-3, segment_angle_rad: 4.71238898}
needle: {radius_m: 5.0e-3, sweep_rad: 1.04719755}
task: {pass_duration_s: 4.0, start_azimuth_rad: 0.2, end_azimuth_rad: 3.3}
)";

std::string ErrorOf(const std::string& yaml) {
  try {
    ParseScene(yaml, "test.yaml");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, ShippedSceneLoads) {
  const std::string dir =
      std::getenv("MICRODEX_SOURCE_DIR") ? std::getenv("MICRODEX_SOURCE_DIR") : ".";
  const SceneModel s = LoadScene(dir + "/assets/scenes/needle_tube.yaml");
  EXPECT_EQ(s.name, "needle-in-tube");
  EXPECT_TRUE(s.HasModule("needle"));
  EXPECT_TRUE(s.HasModule("tremor"));
  EXPECT_FALSE(s.HasModule("thread"));
  EXPECT_DOUBLE_EQ(s.vessel.tube_radius_m, 0.5e-3);
  const SceneModel m = LoadScene(dir + "/assets/scenes/needle_tube_minimal.yaml");
  EXPECT_EQ(m.modules, std::vector<std::string>{"needle"});
}

TEST(Scene, BadInputNamesFileAndField) {
  EXPECT_NE(ErrorOf("name: [").find("test.yaml"), std::string::npos);
  auto has = [](const std::string& err, const char* field) {
    return err.find("test.yaml") != std::string::npos && err.find(field) != std::string::npos;
  };
  std::string y = kGood;
  EXPECT_EQ(ErrorOf(y), "");
  EXPECT_TRUE(has(ErrorOf(y + "colour: red\n"), "colour"));
  std::string bad = y;
  bad.replace(bad.find("tube_radius_m: 0.5e-3"), 21, "tube_radius_m: 6.0e-3");
  EXPECT_TRUE(has(ErrorOf(bad), "vessel.tube_radius_m"));
  bad = y;
  bad.replace(bad.find("end_azimuth_rad: 3.3"), 20, "end_azimuth_rad: 4.0");
  EXPECT_TRUE(has(ErrorOf(bad), "task.end_azimuth_rad"));
  bad = y;
  bad.replace(bad.find("[needle, tremor]"), 16, "[needle, vortex]");
  EXPECT_TRUE(has(ErrorOf(bad), "vortex"));
  bad = y;
  bad.replace(bad.find("radius_m: 5.0e-3, sweep"), 16, "radius_m: abc");
  EXPECT_TRUE(has(ErrorOf(bad), "needle.radius_m"));
  bad = y;
  bad.replace(bad.find("radius_m: 5.0e-3, sweep"), 16, "radius_m: 6.0e-3");
  EXPECT_TRUE(has(ErrorOf(bad), "needle.radius_m"));
  EXPECT_NE(ErrorOf("name: t\nmodules: []\n").find("modules"), std::string::npos);
  try {
    LoadScene("/nonexistent/scene.yaml");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
}

TEST(Scene, IdealPathStaysOnTheCoreCircle) {
  const SceneModel s = ParseScene(kGood, "t");
  EXPECT_DOUBLE_EQ(s.CalcIdealAzimuth(0), s.task.start_azimuth_rad);
  EXPECT_NEAR(s.CalcIdealAzimuth(s.task.pass_duration_s), s.task.end_azimuth_rad, 1e-12);
  EXPECT_NEAR(s.CalcIdealAzimuth(2 * s.task.pass_duration_s), s.task.start_azimuth_rad, 1e-12);
  // Minimum jerk: halfway in time is halfway in angle; the motion starts at rest.
  EXPECT_NEAR(s.CalcIdealAzimuth(s.task.pass_duration_s / 2),
              (s.task.start_azimuth_rad + s.task.end_azimuth_rad) / 2, 1e-12);
  EXPECT_NEAR(s.CalcIdealAzimuth(1e-4), s.task.start_azimuth_rad, 1e-9);
  geometry::ArcDef arc;
  arc.radius_m = s.needle.radius_m;
  arc.sweep_rad = s.needle.sweep_rad;
  geometry::TorusSegmentDef torus;
  torus.core_radius_m = s.vessel.core_radius_m;
  torus.tube_radius_m = s.vessel.tube_radius_m;
  torus.segment_angle_rad = s.vessel.segment_angle_rad;
  for (double t = 0; t < 8; t += 0.37) {
    const Eigen::Isometry3d X_WT = s.CalcIdealX_WT(s.CalcIdealAzimuth(t));
    EXPECT_NEAR(X_WT.translation().head<2>().norm(), s.needle.radius_m, 1e-15);
    arc.X_WN = X_WT * s.X_TN();
    // The ideal needle lies on the core circle: its clearance is the tube radius.
    EXPECT_NEAR(geometry::CalcArcTorusClearanceSampled(arc, torus, 65).clearance_m,
                s.vessel.tube_radius_m, 1e-12);
  }
}

std::string SceneDir() {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes";
}

TEST(Scene, ShippedThreadAndTissueScenesLoad) {
  const SceneModel t = LoadScene(SceneDir() + "/thread_pull.yaml");
  ASSERT_TRUE(t.thread.has_value());
  EXPECT_FALSE(t.tissue.has_value());
  EXPECT_EQ(t.thread->def.num_nodes, 65);
  EXPECT_DOUBLE_EQ(t.thread->def.time_step_s, 1.0 / t.haptic.rate_hz);
  EXPECT_EQ(t.task.path, PathKind::kLine);
  const SceneModel p = LoadScene(SceneDir() + "/tissue_press.yaml");
  ASSERT_TRUE(p.tissue.has_value());
  EXPECT_FALSE(p.thread.has_value());
  EXPECT_EQ(p.tissue->def.level, 6);  // the scene's override of the parameter file
  EXPECT_EQ(p.tissue->def.solver, fem::SolverKind::kPcgIc);
  EXPECT_EQ(p.tissue->tool, TissueToolKind::kBar);
  const SceneModel both = LoadScene(SceneDir() + "/suture_on_tissue.yaml");
  EXPECT_TRUE(both.thread && both.tissue);
}

TEST(Scene, LinePathRunsBetweenItsEndsWithMinimumJerk) {
  const SceneModel s = LoadScene(SceneDir() + "/thread_pull.yaml");
  const double T = s.task.pass_duration_s;
  EXPECT_EQ(s.CalcIdealToolPose(0).translation(), s.task.line_start_m);
  EXPECT_NEAR((s.CalcIdealToolPose(T).translation() - s.task.line_end_m).norm(), 0, 1e-15);
  EXPECT_NEAR((s.CalcIdealToolPose(2 * T).translation() - s.task.line_start_m).norm(), 0, 1e-15);
  EXPECT_NEAR(
      (s.CalcIdealToolPose(T / 2).translation() - 0.5 * (s.task.line_start_m + s.task.line_end_m))
          .norm(),
      0, 1e-15);
  EXPECT_TRUE(s.CalcIdealToolPose(0.3 * T).linear().isApprox(s.task.R_WT_line, 0));
  // On the arc path the pose is the needle's, bit for bit.
  const SceneModel a = ParseScene(kGood, "t");
  for (double t : {0.0, 0.7, 5.1}) {
    EXPECT_TRUE(a.CalcIdealToolPose(t).isApprox(a.CalcIdealX_WT(a.CalcIdealAzimuth(t)), 0));
  }
}

TEST(Scene, ThreadAndTissueSectionsAreChecked) {
  const std::string origin = SceneDir() + "/inline.yaml";
  auto error_of = [&](const std::string& yaml) {
    try {
      ParseScene(yaml, origin);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string line =
      "task: {path: line, line_start_m: [0, 0, 0], line_end_m: [0.01, 0, 0]}\n";
  const std::string thread =
      "thread: {params: thread_stiff_nylon_10_0.yaml, anchor_m: [-0.02, 0, 0]}\n";
  const std::string tissue = "tissue: {params: tissue_skin_patch.yaml, level: 6}\n";
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\n" + thread + line), "");
  EXPECT_EQ(error_of("name: t\nmodules: [tissue]\n" + tissue + line), "");
  EXPECT_NE(error_of("name: t\nmodules: [thread]\n" + line).find("thread"), std::string::npos);
  EXPECT_NE(error_of("name: t\nmodules: [tremor]\n" + thread + line).find("not in modules"),
            std::string::npos);
  const std::string missing =
      error_of("name: t\nmodules: [thread]\nthread: {params: no_such.yaml}\n" + line);
  EXPECT_NE(missing.find("thread.params"), std::string::npos) << missing;
  EXPECT_NE(missing.find("no_such.yaml"), std::string::npos) << missing;
  EXPECT_NE(error_of("name: t\nmodules: [tissue]\n"
                     "tissue: {params: tissue_skin_patch.yaml, display_level: 7}\n" +
                     line)
                .find("tissue.display_level"),
            std::string::npos);
  EXPECT_NE(error_of("name: t\nmodules: [tissue]\n"
                     "tissue: {params: tissue_skin_patch.yaml, solver: magic}\n" +
                     line)
                .find("tissue.solver"),
            std::string::npos);
  EXPECT_NE(error_of("name: t\nmodules: [tissue]\n"
                     "tissue: {params: tissue_skin_patch.yaml, level: 0}\n" +
                     line)
                .find("tissue"),
            std::string::npos);
  EXPECT_NE(error_of("name: t\nmodules: [needle]\n" + line).find("task.path"), std::string::npos);
  EXPECT_NE(error_of("name: t\nmodules: [tremor]\n"
                     "task: {path: line, line_start_m: [0, 0, 0], line_end_m: [0, 0, 0]}\n")
                .find("task.line_end_m"),
            std::string::npos);
  EXPECT_NE(error_of("name: t\nmodules: [thread]\n"
                     "thread: {params: thread_stiff_nylon_10_0.yaml, anchor_m: [-0.02, 0, 0], "
                     "slack_side: [0, 0, 0]}\n" +
                     line)
                .find("thread.slack_side"),
            std::string::npos);
  // The thread must reach the tool's start point without stretching.
  EXPECT_NE(error_of("name: t\nmodules: [thread]\n"
                     "thread: {params: thread_stiff_nylon_10_0.yaml, anchor_m: [-0.05, 0, 0]}\n" +
                     line)
                .find("thread.anchor_m"),
            std::string::npos);
}

}  // namespace
}  // namespace microdex::scene
