// The scene loader: the shipped needle-in-tube scene loads; bad files are refused with the
// file and field named; the ideal path keeps the needle inside the tube.
#include "common/scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

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

TEST(Scene, BadInputNamesFileLineAndField) {
  // kGood's lines: 2 name, 3 modules, 4 vessel, 5 needle, 6 task.
  const std::string y = kGood;
  EXPECT_EQ(ErrorOf(y), "");
  auto with = [&](const char* from, const char* to) {
    std::string bad = y;
    bad.replace(bad.find(from), std::string(from).size(), to);
    return ErrorOf(bad);
  };
  // Unknown keys.
  EXPECT_EQ(ErrorOf(y + "colour: red\n"), "test.yaml:7: colour: unknown key");
  EXPECT_EQ(with("sweep_rad", "sweep_deg"), "test.yaml:5: needle.sweep_deg: unknown key");
  // Wrong types and non-finite numbers.
  EXPECT_EQ(with("radius_m: 5.0e-3, sweep", "radius_m: abc, sweep"),
            "test.yaml:5: needle.radius_m: expected a number");
  EXPECT_EQ(ErrorOf(y + "haptic:\n  max_force_N: 2\n  rate_hz: .nan\n"),
            "test.yaml:9: haptic.rate_hz: expected a finite number");
  EXPECT_EQ(ErrorOf(y + "haptic: {rate_hz: [1000]}\n"),
            "test.yaml:7: haptic.rate_hz: expected a number");
  EXPECT_EQ(ErrorOf(y + "haptic: 3\n"), "test.yaml:7: haptic: expected a map");
  // Values that parse but fail the scene's checks: the line of the field.
  EXPECT_EQ(with("tube_radius_m: 0.5e-3", "tube_radius_m: 6.0e-3"),
            "test.yaml:4: vessel.tube_radius_m: expected 0 < tube radius < core radius");
  EXPECT_EQ(with("end_azimuth_rad: 3.3", "end_azimuth_rad: 4.0"),
            "test.yaml:6: task.end_azimuth_rad: expected end + needle sweep <= vessel segment "
            "angle");
  EXPECT_EQ(with("[needle, tremor]", "[needle, vortex]"),
            "test.yaml:3: modules: unknown module 'vortex' (known: needle, tremor, thread, "
            "tissue, grasp, loop, knots, placement)");
  EXPECT_EQ(with("radius_m: 5.0e-3, sweep", "radius_m: 6.0e-3, sweep"),
            "test.yaml:5: needle.radius_m: expected within the tube: |needle radius − core "
            "radius| < tube radius");
  EXPECT_EQ(ErrorOf("name: t\nmodules: []\n"),
            "test.yaml:2: modules: expected at least one module");
  // A field left at its default, or missing: the line of its map.
  EXPECT_EQ(ErrorOf("# no name\nmodules: [needle]\n"),
            "test.yaml:2: name: expected a non-empty name");
  EXPECT_EQ(ErrorOf("name: t\n"), "test.yaml:1: modules: missing");
  // Files that do not parse, or are not a map.
  const std::string malformed = ErrorOf("name: t\nmodules: [needle\n");
  EXPECT_EQ(malformed.rfind("test.yaml:3: malformed YAML: ", 0), 0u) << malformed;
  EXPECT_EQ(ErrorOf("- needle\n"), "test.yaml:1: expected a map at the top");
  try {
    LoadScene("/nonexistent/scene.yaml");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/scene.yaml: cannot open file");
  }
  // SceneError is an InputError.
  EXPECT_THROW(ParseScene("name: [", "test.yaml"), InputError);
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
  EXPECT_EQ(p.tissue->def.solver, fem::SolverKind::kPcgDic);
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
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\n" + line),
            origin + ":1: thread: section required by the 'thread' module");
  EXPECT_EQ(error_of("name: t\nmodules: [tremor]\n" + thread + line),
            origin + ":3: thread: section given but 'thread' is not in modules");
  // A parameter file that cannot be opened: the scene's params line.
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\nthread: {params: no_such.yaml}\n" + line),
            origin + ":3: thread.params: cannot open file " + SceneDir() + "/no_such.yaml");
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\nthread: {anchor_m: [-0.02, 0, 0]}\n" + line),
            origin + ":3: thread.params: missing");
  // Any other error in a parameter file names that file and its line.
  const std::string bad_thread = ::testing::TempDir() + "/scene_bad_thread.yaml";
  std::ofstream(bad_thread) << "thread:\n  base: stiff-nylon-10-0\n  num_nodes: 2\n";
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\nthread: {params: " + bad_thread +
                     ", anchor_m: [-0.02, 0, 0]}\n" + line),
            bad_thread + ":3: thread.num_nodes: expected an integer in [3, 100000]");
  EXPECT_EQ(error_of("name: t\nmodules: [tissue]\n"
                     "tissue: {params: tissue_skin_patch.yaml, display_level: 7}\n" +
                     line),
            origin + ":3: tissue.display_level: expected 1..6 ((2^l + 1)^2 <= 16384 values)");
  EXPECT_EQ(
      error_of("name: t\nmodules: [tissue]\n"
               "tissue: {params: tissue_skin_patch.yaml, solver: magic}\n" +
               line),
      origin +
          ":3: tissue.solver: solver 'magic': expected cg, pcg_jacobi, pcg_ic, pcg_dic or cholmod");
  // The scene's overrides are checked with the parameter file's other values.
  EXPECT_EQ(error_of("name: t\nmodules: [tissue]\n"
                     "tissue:\n  params: tissue_skin_patch.yaml\n  level: 0\n" +
                     line),
            origin + ":5: tissue.level: expected an integer in [1, max_level] (" + SceneDir() +
                "/tissue_skin_patch.yaml with the scene's overrides)");
  EXPECT_EQ(error_of("name: t\nmodules: [needle]\n" + line),
            origin + ":3: task.path: the needle module needs path: arc");
  EXPECT_EQ(error_of("name: t\nmodules: [tremor]\n"
                     "task: {path: line, line_start_m: [0, 0, 0], line_end_m: [0, 0, 0]}\n")
                .rfind(origin + ":3: task.line_end_m: ", 0),
            0u);
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\n"
                     "thread: {params: thread_stiff_nylon_10_0.yaml, anchor_m: [-0.02, 0, 0], "
                     "slack_side: [0, 0, 0]}\n" +
                     line)
                .rfind(origin + ":3: thread.slack_side: ", 0),
            0u);
  // The thread must reach the tool's start point without stretching.
  EXPECT_EQ(error_of("name: t\nmodules: [thread]\n"
                     "thread: {params: thread_stiff_nylon_10_0.yaml, anchor_m: [-0.05, 0, 0]}\n" +
                     line)
                .rfind(origin + ":3: thread.anchor_m: ", 0),
            0u);
}

}  // namespace
}  // namespace microdex::scene

namespace microdex::scene {
namespace {

// A training scene: its task, scoring terms, microscope, visual meshes (loaded through
// assimp) and default cues.
TEST(Scene, TrainingScenesLoadWithTaskScoringAndMeshes) {
  const SceneModel h = LoadScene(SceneDir() + "/tremor_hold.yaml");
  EXPECT_EQ(h.task.kind, TaskKind::kTremorHold);
  EXPECT_DOUBLE_EQ(h.task.hold_s, 10);
  EXPECT_EQ(h.scoring.size(), 3u);
  EXPECT_DOUBLE_EQ(h.microscope.magnification, 20);
  ASSERT_EQ(h.visuals.size(), 2u);  // in the order of kVisualRoles
  EXPECT_EQ(h.visuals[0].role, "forceps");
  EXPECT_EQ(h.visuals[1].role, "target");
  EXPECT_NEAR(h.visuals[1].X_PM.translation().z(), 0.002, 1e-15);
  // A hold's ideal pose is the target at every time.
  EXPECT_TRUE(h.CalcIdealToolPose(3.7).translation().isApprox(h.task.target_m));
  // The loop along a wire: the ideal pose starts at the course's start and ends at its end,
  // with the loop's axis along the wire.
  const SceneModel w = LoadScene(SceneDir() + "/loop_along_wire.yaml");
  ASSERT_TRUE(w.loop.has_value());
  EXPECT_EQ(w.task.kind, TaskKind::kLoopAlongWire);
  const Eigen::Isometry3d X0 = w.CalcIdealToolPose(0);
  EXPECT_LT((X0.translation() - w.loop->wire.pieces.front().StartPoint()).norm(), 1e-12);
  EXPECT_LT((X0.linear().col(2) -
             (w.loop->wire.pieces.front().p_W1 - w.loop->wire.pieces.front().p_W0).normalized())
                .norm(),
            1e-12);
  const Eigen::Isometry3d X1 = w.CalcIdealToolPose(w.task.pass_duration_s);
  EXPECT_LT((X1.translation() - w.loop->wire.pieces.back().EndPoint()).norm(), 1e-9);
  // A bad course step names the step.
  std::string course = std::string(kGood) + "loop: {course: {steps: [straight 0.01, wiggle 3]}}\n";
  course.replace(course.find("[needle, tremor]"), 16, "[needle, loop]");
  EXPECT_EQ(ErrorOf(course),
            "test.yaml:7: loop.course.steps: 'wiggle 3': expected 'straight LENGTH_M' or "
            "'turn RADIUS_M ANGLE_RAD [PLANE_RAD]'");
  const SceneModel n = LoadScene(SceneDir() + "/needle_along_tube.yaml");
  EXPECT_EQ(n.task.kind, TaskKind::kNeedleAlongTube);
  EXPECT_EQ(n.task.passes, 2);
}

// Bad task, scoring, cue and mesh fields name the file, line and field.
TEST(Scene, BadTrainingFieldsNameFileLineAndField) {
  const std::string base = std::string(kGood) + "task: {kind: needle_along_tube}\n";
  std::string y = kGood;
  EXPECT_EQ(ErrorOf(y + "scoring: {speed: {limit: 1}}\n"),
            "test.yaml:7: scoring.speed: unknown key");
  EXPECT_EQ(ErrorOf(y + "scoring: {time_s: {limit: 0}}\n"),
            "test.yaml:7: scoring.time_s.limit: expected > 0");
  EXPECT_EQ(ErrorOf(y + "cues: {on: {tremor: 50}}\n"),
            "test.yaml:7: cues.on.amplified_tremor: gain: expected a finite number in [1, 20] for "
            "amplified_tremor, got 50");
  EXPECT_EQ(ErrorOf(y + "cues: {on: {convergent: 2.0e6}}\n"),
            "test.yaml:7: cues.on.convergent: stiffness_N_per_m: expected a finite number in [0, "
            "1e+06] for convergent, got 2e+06");
  EXPECT_EQ(ErrorOf(y + "cues: {on: {vortex: 1}}\n"), "test.yaml:7: cues.on.vortex: unknown key");
  EXPECT_EQ(ErrorOf(y + "microscope: {magnification: 0}\n"),
            "test.yaml:7: microscope.magnification: expected 1..50 (a surgical microscope: 10–20)");
  std::string kind = kGood;
  kind.replace(kind.find("task: {"), 7, "task: {kind: juggling, ");
  EXPECT_EQ(ErrorOf(kind),
            "test.yaml:6: task.kind: expected follow_path, tremor_hold, needle_along_tube, "
            "grasp, loop_along_wire, knot_topology, knot_placement, nylon_loop, "
            "needle_through_tissue or knot_tying");
  kind = kGood;
  kind.replace(kind.find("task: {"), 7, "task: {kind: tremor_hold, ");
  EXPECT_EQ(ErrorOf(kind), "test.yaml:2: scoring: required by task kind tremor_hold");
  // Meshes: missing, empty and unreadable files are the scene's error at the mesh field.
  std::string dir = ::testing::TempDir();
  if (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  std::ofstream(dir + "/empty.obj").close();
  std::ofstream(dir + "/garbage.ply") << "ply\nthis is not a mesh\n";
  for (const char* file : {"missing.obj", "empty.obj", "garbage.ply"}) {
    const std::string yaml = y + "visuals:\n  vessel: {mesh: " + file + "}\n";
    std::string what;
    try {
      ParseScene(yaml, dir + "/scene.yaml");
    } catch (const SceneError& e) {
      what = e.what();
    }
    EXPECT_EQ(what.rfind(dir + "/scene.yaml:8: visuals.vessel.mesh: " + dir + "/" + file, 0), 0u)
        << "[" << what << "]";
  }
}

}  // namespace
}  // namespace microdex::scene
