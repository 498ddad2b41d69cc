#pragma once
// A scene: the immutable description of one training task (the scene is never changed
// by a run; everything that changes is the station state, common/state), loaded
// once from YAML and validated. It names the modules a station builds; a station builds only
// those and publishes only their topics.
//
// Modules: the needle-in-tube primitive (thesis §2.2, Fig. 2.2c: "needle maneuvering along a
// curved tube": a curved needle held at its tail slides along a tube, the segment of a torus,
// without touching its wall), the tremor estimate, the suture thread (chapter 5: one end held
// by the tool, the other anchored at the stitch) and the tissue patch (chapter 3: pressed by
// the tool tip). The thread and tissue take their material from the parameter files
// assets/scenes/thread_*.yaml and tissue_*.yaml, named relative to the scene file.

#include <Eigen/Geometry>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/base/input_error.h"
#include "common/cues/cue_kind.h"
#include "common/fem/tissue_def.h"
#include "common/geometry/arc_torus.h"
#include "common/geometry/loop_wire.h"
#include "common/grasp/grasp_def.h"
#include "common/knot/stitch_knot.h"
#include "common/puncture/puncture.h"
#include "common/thread/knot_tie.h"
#include "common/thread/thread_def.h"

namespace microdex::scene {

// Bad scene file (or a parameter file it names): an InputError, "FILE:LINE: field: reason".
class SceneError : public InputError {
 public:
  using InputError::InputError;
  explicit SceneError(const InputError& e) : InputError(e) {}
};

// Modules a scene may name; "thread" and "tissue" need their scene sections.
inline constexpr const char* kKnownModules[] = {"needle", "tremor", "thread", "tissue",
                                                "grasp",  "loop",   "knots",  "placement"};

// The tube is a geometry::TorusSegmentDef (scene section `vessel`: core_radius_m,
// tube_radius_m, segment_angle_rad, position_m, rpy_rad). The needle is a geometry::ArcDef
// (section `needle`: radius_m, sweep_rad) held at its s = 0 end by the tool; its X_WN is the
// needle's pose at the start of the task (CalcIdealX_WT(start azimuth) * X_TN()).

// The ideal tool path the simulated trainee follows and the guidance fields pull towards.
enum class PathKind {
  kArc,     // the needle tail on its path circle around the vessel axis (start/end azimuth)
  kLine,    // a straight segment from line_start_m to line_end_m, fixed tool orientation
  kCircle,  // the tool tip on a horizontal circle (circle_center_m, circle_radius_m) from the
            // start to the end azimuth, fixed tool orientation
};

// What the trainee is asked to do (assets/scenes/README.md, "Tasks"): the dexterity primitives
// of thesis §2.2 and the demos of the single modules.
enum class TaskKind {
  kFollowPath,       // passes along the path; scored by time without fault (module demos)
  kTremorHold,       // hold the tool tip on target_m for hold_s under magnification
  kNeedleAlongTube,  // slide the needle along the tube and back, `passes` passes, no touching
  kGrasp,            // close the forceps on the object, lift it to lift_height_m, hold it hold_s
  kLoopAlongWire,    // pass the held loop along the wire course to its end without touching
  kKnotTopology,     // name each knot shown (square, granny, surgeon's, slip, half hitch)
  kKnotPlacement,    // place stitches evenly around the vessel's cut end, a bite from the edge
  kNylonLoop,        // lay the grasped nylon in a loop matching the target shape
  kNeedleThroughTissue,  // drive the needle through the tissue along its circle, in and out
  kKnotTying,            // tie a knot around the stitch with the needle holder and forceps
};
// follow_path, tremor_hold, needle_along_tube, grasp, loop_along_wire, knot_topology,
// knot_placement, nylon_loop, needle_through_tissue, knot_tying
const char* TaskKindName(TaskKind kind);
TaskKind ParseTaskKind(const std::string& text);  // throws std::invalid_argument

// The task: passes along the path from start to end and back, each pass lasting
// pass_duration_s (minimum-jerk timing) for the scripted ideal; the task ends when the tool
// has made `passes` passes (or, for a hold, after hold_s) or at time_limit_s.
struct TaskDef {
  TaskKind kind = TaskKind::kFollowPath;
  int passes = 2;
  double time_limit_s = 60;
  // How far from the ideal path (or the target) the tool may be and still count as on it.
  double tolerance_m = 0.5e-3;
  Eigen::Vector3d target_m = Eigen::Vector3d::Zero();  // kTremorHold, world
  double hold_s = 10;                                  // kTremorHold
  double pass_duration_s = 4.0;
  PathKind path = PathKind::kArc;
  double start_azimuth_rad = 0.2;  // kArc
  double end_azimuth_rad = 3.3;
  Eigen::Vector3d circle_center_m = Eigen::Vector3d::Zero();  // kCircle, world
  double circle_radius_m = 5e-3;                              // kCircle
  Eigen::Vector3d line_start_m = Eigen::Vector3d::Zero();     // kLine, world
  Eigen::Vector3d line_end_m = Eigen::Vector3d(0.01, 0, 0);
  Eigen::Matrix3d R_WT_line = Eigen::Matrix3d::Identity();  // kLine tool orientation
};

// The suture thread (station "thread" module): a ThreadDef from a parameter file, node 0
// held fixed at the anchor (the stitch), the last node grasped by the tool tip. At the start
// the thread runs from the anchor to the tool's ideal start point, with its slack (thread
// longer than that distance) taken up by a circular arc bowed towards slack_side, so the
// grasped node starts at the tool and every link at its rest length.
struct ThreadSceneDef {
  std::string params_path;  // the parameter file, resolved against the scene's folder
  thread::ThreadDef def;    // loaded from params_path; time step set to the haptic period
  Eigen::Vector3d p_W_anchor = Eigen::Vector3d::Zero();
  // The side a slack thread bows towards at the start (unit; its part along the anchor–tool
  // line is ignored).
  Eigen::Vector3d slack_side_W = Eigen::Vector3d::UnitZ();
  // A floor the thread rests on (plane z = floor_height_m, normal +z); NaN: none.
  double floor_height_m = std::numeric_limits<double>::quiet_NaN();
  // A step whose largest link strain exceeds this is a fault (an overstretched suture).
  double max_strain = 0.05;
};

// The tool tip pressing the tissue: a point (with a contact radius) or a short bar along the
// tool's x axis centred at the tip; or the curved needle (the scene's `needle`, held at its
// tail), which pierces the tissue (common/puncture, scene section `puncture`).
enum class TissueToolKind { kPoint, kBar, kNeedle };

// The tissue patch (station "tissue" module): a TissueDef from a parameter file, with the
// scene's overrides of the mesh level and solver, placed at X_WS (the patch corner; the
// patch is [0, Lx] × [0, Ly] in S's xy plane, surface at z = 0, z out of the tissue).
struct TissueSceneDef {
  std::string params_path;
  fem::TissueDef def;
  Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();
  TissueToolKind tool = TissueToolKind::kPoint;
  double contact_radius_m = 0.5e-3;  // point tool
  double bar_length_m = 4e-3;        // bar tool
  // Level of the uniform grid the displacement field is published on: (2^l + 1)² values,
  // l <= 6 keeps it within TissueState's bound of 16384.
  int display_level = 6;
  // A step whose reaction force exceeds this is a fault (pressing too hard).
  double max_force_N = 0.5;
};

// The needle through tissue (tissue.tool: needle): the puncture model's parameters and where
// the needle should go in and come out, in world.
struct PunctureSceneDef {
  puncture::PunctureDef def;
  Eigen::Vector3d p_W_entry_target = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_W_exit_target = Eigen::Vector3d::Zero();
};

// The grasping primitive (station "grasp" module, thesis §2.2, Fig. 2.2d): a small object on
// the table (the plane z = 0 of world) and the forceps' jaws on the tool (common/grasp). The
// task line runs from above the object down to it: the simulated trainee descends, closes the
// jaws, lifts back along the line and holds.
struct GraspSceneDef {
  grasp::GraspDef def;
  Eigen::Vector3d p_W_object = Eigen::Vector3d(0, 0, 0.5e-3);  // centre of mass on the table
  double yaw_rad = 0;                                          // the object's turn about z
  double lift_height_m = 3e-3;  // the centre of mass this high above the table counts as lifted
};

// The loop along a wire (station "loop" module, thesis §2.2, Fig. 2.2b): the tool holds a loop
// (its frame L is the tool frame T: the loop's circle in T's xy plane, around T's origin) and
// passes it along a wire course of straight runs and turns (common/geometry/loop_wire.h). The
// ideal path is the wire's axis, the loop's plane across it.
struct LoopSceneDef {
  geometry::LoopDef loop;
  geometry::WireDef wire;
  double wall_stiffness_N_per_m = 500;  // penalty force of the wire on contact
};

// Knot topology (station "knots" module, thesis §2.2, Fig. 2.2f): knots tied around a stitch
// (common/knot/stitch_knot_shapes.h) are shown one by one; the trainee names each with the
// device's buttons (the button value is the class: 1 square, 2 granny, 3 surgeon's, 4 slip,
// 5 half hitch). Each shown knot is checked at load by the recogniser.
struct KnotQuizSceneDef {
  std::vector<knot::StitchKnotType> items;  // shown in this order
  double thread_diameter_m = 30e-6;         // 10-0 nylon
  // Knots tied by the thread module around a stitch (`knots.tied`: class -> OBJ polyline in
  // the tissue's frame, written by microdex-bench thread --tie ... --stitch --obj or
  // microdex-bench stitch --obj-dir), read at load. A class without one is drawn
  // parametrically (knot::QuizItemShapeDef).
  struct TiedKnot {
    knot::StitchKnotType type = knot::StitchKnotType::kNone;
    std::vector<Eigen::Vector3d> shape;  // cropped, centred and scaled for the view
    // The file's thread diameter (`# thread_diameter_m`, knot/obj.h) at the shape's scale;
    // 0 for a file without one (the recogniser then takes the median link).
    double thread_diameter_m = 0.0;
  };
  std::vector<TiedKnot> tied;
  // The thread shown as item i: the tied knot of its class (its mirror image, x -> -x, for
  // every second item of that class), or the parametric shape.
  std::vector<Eigen::Vector3d> ItemShape(std::size_t i) const;
  // The diameter to recognise item i's shape with (knot::StitchKnotOptions): the tied knot's,
  // or thread_diameter_m for a parametric shape.
  double ItemThreadDiameter(std::size_t i) const;
};

// Knot placement (station "placement" module, thesis §2.2: "microsurgeons place knots evenly
// around the whole section, at a constant distance from the end"): a vessel along world z with
// its cut end at z = end_height_m; the trainee touches the tool tip to the vessel wall where a
// stitch goes and presses a button. A stitch is recorded at the tip's azimuth about the vessel
// axis and its distance below the cut edge.
struct PlacementSceneDef {
  double vessel_radius_m = 0.5e-3;  // outer radius of the vessel (1 mm across)
  double end_height_m = 6e-3;       // z of the cut end
  int stitches = 8;                 // to place, evenly: 2π / stitches apart
  double bite_m = 0.3e-3;           // the distance from the edge each should have
  double move_s = 1.5;              // the scripted time from one stitch to the next
};

// Knot tying (task kind knot_tying, with the thread module and a second hand): the thread is
// laid through a stitch (thread::KnotStitchDef, in the scene's frame: the thread along +x,
// y up, the tissue surface the plane y = surface_y_m) and held at node 0 by the forceps (the
// second tool) and at its last node by the needle holder (the first tool). The trainee ties
// `throws` throws, choosing each with the device's buttons (1 a single right-handed throw,
// 2 single left, 3 double right, 4 double left); once all are chosen the throws are tied one
// after the other: the instrument tie of each (loop, wraps, exit) is guided along the jig's path at
// speed_m_per_s (thread::KnotThrowScript), the release and the pull to pull_tension_N follow. After
// the last throw both hands hold hold_tension_N for hold_s, and the two hands' deviations from
// their rest poses move the thread's ends. The jig of throw 1 sits at first_jig_x_m on the standing
// part, that of the next throws at next_jig_x_m (3 mm beyond the first knot, which the pull lays
// between the first puncture and the bite).
struct KnotTyingSceneDef {
  thread::KnotStitchDef stitch;
  int throws = 2;
  double speed_m_per_s = 4e-3;
  double pull_tension_N = 10e-3;
  // Each hand limits its pull to pull_tension_N (thread::KnotThrowOptions::force_limited_pull):
  // with both hands pulled by position a double throw loses a pass around the stitch.
  bool force_limited_pull = true;
  double throw_tension_N = 2e-3;  // the standing hand's tension while a throw is wrapped
  double hold_tension_N = 20e-3;
  // In the hold, a hand held d further out along the thread than its rest pulls its end with
  // hold_tension_N + hold_pull_N_per_m d (thread::KnotHoldOptions::pull_gain_N_per_m): the
  // trainee sets the tension. 0: the hands keep hold_tension_N whatever the trainee does.
  double hold_pull_N_per_m = 0.0;
  double hold_s = 2.0;
  double first_jig_x_m = 4e-3;
  double next_jig_x_m = 4.66e-3;
  double surface_y_m = -0.35e-3;
  // With the tissue module: the stitch moves with the patch under the suture's pull. Each rod
  // (the bite and the two punctures) takes the patch's normal displacement under the loads
  // the thread presses on the rods, the patch's point compliance (fem::CalcPointCompliance)
  // times those loads low-passed with this time constant (the tissue's relaxation), s. 0: a
  // rigid stitch. Too short a time for the thread's stiffness on the patch's compliance is an
  // error naming this field (station/thread_module.cc).
  double stitch_relax_s = 0.5;
  // The bite cuts through the tissue (cheese-wiring) while the suture's low-passed load on it
  // along the patch's normal exceeds this, N: the cut grows at the rate the patch would follow
  // the excess (its compliance at the bite times the excess, over stitch_relax_s), and the
  // bite is pulled out once the thread under it has cut up to the surface. 0: it never tears.
  // Needs the stitch on the tissue (stitch_relax_s > 0).
  double bite_tear_N = 0.0;
  // The stitch also moves in the patch's plane: the thread's loads along the surface (the legs
  // drawing the punctures together) displace the rods by the patch's in-plane (plane-stress)
  // compliance (fem::CalcInPlaneCompliance, Poisson's ratio from the tissue file), low-passed
  // alike. Needs the stitch on the tissue (stitch_relax_s > 0).
  bool stitch_in_plane = false;
};

// Haptic rendering limits.
struct HapticDef {
  double rate_hz = 1000;
  double max_force_N = 2.0;                // every force sent to a device is saturated here
  double max_torque_Nm = 0.05;             // and every torque (about the tool point) here
  double wall_stiffness_N_per_m = 1000.0;  // penalty force of the tube wall on contact
};

// A term of the score: the metric's value v scores weight · clamp(1 − v / limit, 0, 1); the
// score is 100 Σ points / Σ weights (station/score.h lists the metrics).
struct ScoreTermDef {
  std::string metric;
  double weight = 1;
  double limit = 1;  // the value that scores nothing, in the metric's unit
};

// The view through the microscope (the station's view and the instructor's mirror).
struct MicroscopeDef {
  double magnification = 15;                               // 10–20×
  Eigen::Vector3d look_at_m = Eigen::Vector3d::Zero();     // world
  Eigen::Vector3d view_dir_W = -Eigen::Vector3d::UnitZ();  // from the objective to look_at
};

// A mesh the views draw (the physics keeps its analytic shapes): role, file, pose. The pose of
// a held role (needle, forceps, needle_holder, loop) is in the tool frame T, the others' in
// world; a mesh file is in metres (common/mesh/README.md).
inline constexpr const char* kVisualRoles[] = {"vessel", "needle", "tissue", "forceps",
                                               "wire",   "loop",   "target", "needle_holder"};
struct VisualDef {
  std::string role;
  std::string mesh_path;  // resolved against the scene's folder; checked readable at load
  Eigen::Isometry3d X_PM = Eigen::Isometry3d::Identity();  // P: world, or T when held
};

// A second tool, held in the trainee's other hand (bimanual tasks: the forceps beside the
// needle holder). Its device is the station's second device; its scripted ideal pose (what the
// simulated trainee's other hand follows) is a hold at X_WT_start. With the thread module, the
// second tool holds the thread's node 0 (instead of the fixed anchor), starting at
// thread.anchor_m, which must then be the second tool's position.
struct SecondHandDef {
  Eigen::Isometry3d X_WT_start = Eigen::Isometry3d::Identity();
};

// The cues a scene offers and those on from its first step.
struct CueSetDef {
  std::vector<cues::CueKind> available;              // empty: every kind
  std::vector<std::pair<cues::CueKind, double>> on;  // kind, parameter
};

struct SceneModel {
  std::string path;  // where it was loaded from ("" when parsed from text)
  std::string name;
  std::vector<std::string> modules;
  geometry::TorusSegmentDef vessel{5e-3, 0.5e-3, 4.71238898038469,  // 270°
                                   Eigen::Isometry3d::Identity()};
  geometry::ArcDef needle{5e-3, 1.0471975511965976,  // 60°
                          Eigen::Isometry3d::Identity()};
  TaskDef task;
  HapticDef haptic;
  std::optional<ThreadSceneDef> thread;         // present exactly when modules has "thread"
  std::optional<TissueSceneDef> tissue;         // present exactly when modules has "tissue"
  std::optional<PunctureSceneDef> puncture;     // present exactly when tissue.tool is needle
  std::optional<GraspSceneDef> grasp;           // present exactly when modules has "grasp"
  std::optional<LoopSceneDef> loop;             // present exactly when modules has "loop"
  std::optional<KnotQuizSceneDef> knots;        // present exactly when modules has "knots"
  std::optional<PlacementSceneDef> placement;   // present exactly when modules has "placement"
  std::optional<KnotTyingSceneDef> knot_tying;  // present exactly when task.kind is knot_tying
  std::vector<ScoreTermDef> scoring;            // empty for kFollowPath (its own formula)
  MicroscopeDef microscope;
  std::vector<VisualDef> visuals;
  CueSetDef cues;
  std::optional<SecondHandDef> second_hand;  // present in bimanual scenes

  bool HasModule(const std::string& module) const;
  // The scripted ideal tool pose at azimuth theta: the needle tail on its path circle (radius
  // needle.radius_m about the vessel axis), the needle lying along the core circle.
  Eigen::Isometry3d CalcIdealX_WT(double theta_rad) const;
  // The scripted azimuth of the tool at time t: passes from start to end and back, each with
  // minimum-jerk timing θ = a + (b − a)(10τ³ − 15τ⁴ + 6τ⁵), τ the fraction of the pass.
  double CalcIdealAzimuth(double t_s) const;
  // The fraction of the path at time t (0 at the start, 1 at the end), same timing.
  double CalcIdealPathFraction(double t_s) const;
  // The scripted ideal tool pose at time t along the task's path (a hold: the target; the loop
  // along a wire: the loop centred on the wire's axis, its plane across the wire).
  Eigen::Isometry3d CalcIdealToolPose(double t_s) const;
  // Bimanual scenes: the scripted ideal pose of the second tool at time t.
  Eigen::Isometry3d CalcIdealSecondToolPose(double t_s) const;
  // The number of tools (devices) the scene's trainee holds: 1, or 2 with a second_hand.
  int hands() const { return second_hand ? 2 : 1; }
  // The needle frame N from the tool frame T (the tail point, s = 0): X_WN = X_WT * X_TN.
  Eigen::Isometry3d X_TN() const;
};

// The pose on a wire course at a fraction of its length (0 start, 1 end): on the wire's axis,
// z along its tangent.
Eigen::Isometry3d CalcWireCoursePose(const geometry::WireDef& wire, double fraction);

// The scene's own checks (and those of its thread and tissue definitions), called by the
// loaders. Throws std::invalid_argument for the first bad field, whose message starts with the
// field name followed by ': ' (e.g. `vessel.tube_radius_m: expected 0 < tube radius < core
// radius`); the loaders rethrow it as SceneError at that field's line.
void ValidateScene(const SceneModel& scene);

// Loads and validates a scene file. Throws SceneError "FILE:LINE: field: reason" (for an error
// in a parameter file the scene names, FILE and LINE are the parameter file's).
SceneModel LoadScene(const std::string& path);
// The same from YAML text; origin stands for the file in error messages.
SceneModel ParseScene(const std::string& yaml_text, const std::string& origin);

}  // namespace microdex::scene
