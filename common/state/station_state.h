#pragma once
// StationState: everything that changes while a station runs, as one plain value (copyable,
// comparable, hashable; no pointer into another object). The scene and the modules' models
// are immutable after loading; caches derived from the state (the thread's factorisation and
// sphere BVH, the tissue's mesh selection, patterns and factors) live in the modules'
// workspaces and are rebuilt from the state, so a copy of this value is all a mirror, a
// recording, a replay or a "what if" branch needs.
//
// One step of a station (station/station_step.h) reads the device sample and the cue requests
// of that step and writes this value; nothing else holds simulation state. The snapshot the
// haptic thread hands to the publisher is a projection of it (ProjectSnapshot).
//
// Every field is listed once, in VisitStationState (station_state_visit.h): the hash, the
// equality and the tests walk that one list.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>

#include "common/cues/cue_kind.h"
#include "common/cues/end_point_predictor.h"
#include "common/cues/tremor_filter.h"
#include "common/fem/tissue_step.h"
#include "common/geometry/arc_torus.h"
#include "common/geometry/loop_wire.h"
#include "common/grasp/grasp_model.h"
#include "common/puncture/puncture.h"
#include "common/thread/knot_tie.h"
#include "common/thread/thread_model.h"

namespace microdex::state {

inline constexpr int kMaxPendingCues = 32;
inline constexpr int kMaxAcksPerStep = 4;

// A cue as it enters the simulation: applied at the first step >= apply_at_step. `off`
// switches the kind off (param unused).
struct CueRequest {
  std::uint64_t cue_id = 0;
  cues::CueKind kind = cues::CueKind::kClear;
  double param = 0;
  std::uint64_t apply_at_step = 0;
  bool off = false;
};

// A cue applied during a step (reported back with that step).
struct CueAck {
  std::uint64_t cue_id = 0;
  cues::CueKind kind = cues::CueKind::kClear;
  double param = 0;
  bool off = false;
};

// The device as the station last read it, and the tool after the cues.
struct ToolState {
  Eigen::Isometry3d X_WT_device = Eigen::Isometry3d::Identity();  // raw device sample
  double gripper = 0;                                             // 0 open .. 1 closed
  std::uint32_t buttons = 0;
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  // tool after cues (what modules see)
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();  // force sent to the device: finite, saturated
  // Torque sent to the device about the tool point (X_WT's origin), world, N m: finite,
  // saturated at haptic.max_torque_Nm (zero where no module pushes off-centre).
  Eigen::Vector3d tau_T_W = Eigen::Vector3d::Zero();
  std::uint32_t force_warnings = 0;  // non-finite forces replaced by zero, running count
  // The device's fault this step (station::DeviceFault: 0 none; 1 timeout, 2 non-finite,
  // 3 jump): the pose is the last valid one, held, and the force is ramped to zero.
  std::uint8_t device_fault = 0;
};

// The end-point predictor of the current sub-movement (common/cues/end_point_predictor.h).
struct PredictorState {
  cues::EndPointPredictorState predictor;             // with the warning (predictor.warning)
  Eigen::Vector3d p_W_end = Eigen::Vector3d::Zero();  // predicted end point (the last valid)
  double error_m = 0;                                 // its distance from the path or target
  std::uint8_t valid = 0;                             // a prediction this step
};

// The learning cues in force and the ones waiting for their step.
struct CueState {
  // Bit cues::CueBit(kind) per kind switched on: the wall, as the scene has it, at first.
  std::uint32_t active = cues::CueBit(cues::CueKind::kWall);
  // The parameter of each kind (CueParamLimits; kept when the kind is switched off).
  std::array<double, cues::kCueKindCount> param = cues::kCueParamDefaults;
  // The 8–12 Hz band of the raw device motion, filtered every step (so that switching the
  // amplification on is seamless); the tremor module's RMS reads the same band.
  cues::TremorFilterState tremor_filter;
  Eigen::Vector3d tremor_band_m = Eigen::Vector3d::Zero();  // this step's band-passed position
  // What the visual and audio cues show and sound this step (common/cues/audio_synth.h,
  // cue_overlay.h), computed every step whether or not they are on.
  double clearance_m = 0;  // the tool's clearance to the task's walls (+inf: none)
  double deviation_m = 0;  // the tool's distance from the ideal path
  Eigen::Vector3d p_W_nearest = Eigen::Vector3d::Zero();  // the path point nearest the tool
  std::uint8_t click = 0;                                 // a contact began this step
  std::uint8_t error = 0;                                 // at fault this step
  PredictorState prediction;
  // The force limiter (common/cues/force_limits.h): steps its rate limit clipped, running count.
  std::uint32_t force_rate_limited = 0;
  Eigen::Vector3d f_cue_W = Eigen::Vector3d::Zero();  // the cue's force as limited, last step
  std::array<CueRequest, kMaxPendingCues> pending{};
  int pending_count = 0;
  std::array<CueAck, kMaxAcksPerStep> acks{};  // applied during this step
  int ack_count = 0;

  bool on(cues::CueKind kind) const { return (active & cues::CueBit(kind)) != 0; }
  double p(cues::CueKind kind) const { return param[static_cast<std::size_t>(kind)]; }
};

// Running totals of the task score (station/score.h), updated every step.
struct ScoreState {
  double time_s = 0;
  double time_in_contact_s = 0;
  std::uint32_t contacts = 0;  // fault episodes
  double clearance_sum_m = 0;  // needle module only
  std::uint64_t clearance_samples = 0;
  double min_clearance_m = 0;  // +inf until the first sample
  double path_length_m = 0;
  double ideal_path_length_m = 0;
  double tremor_sq_sum_m2 = 0;
  std::uint64_t tremor_samples = 0;
  // A fault episode (needle contact, overstretched thread, tissue pressed too hard) ends after
  // kContactReleaseSteps steps without fault, so tremor at the limit is not hundreds of them.
  std::uint8_t in_episode = 0;
  std::int32_t steps_free = 0;
  std::uint8_t have_prev = 0;
  std::array<double, 3> p_WT_device_prev{};  // (plain arrays: the snapshot copies this struct
  std::array<double, 3> p_WT_ideal_prev{};   // as plain data)
  // The task (scene::TaskDef): the device's distance from the ideal path (or the hold target)
  // and its slow part (the tremor band removed), the time beyond the tolerance, the progress.
  double deviation_sum_m = 0;
  double deviation_max_m = 0;
  double drift_sum_m = 0;
  std::uint64_t deviation_samples = 0;
  double time_outside_s = 0;
  double progress = 0;  // along the path in the current pass, 0 start .. 1 end
  std::int32_t passes_done = 0;
  std::uint8_t outcome = 0;    // TaskOutcome: 0 running, 1 completed, 2 time limit
  std::uint64_t end_step = 0;  // the step at which the task ended
  double goal_time_s = 0;      // grasp: time with the object held at the lift height
  // The grasp module's metrics, copied for the score (common/grasp/README.md "Metrics").
  double object_rotation_rad = 0;  // largest induced rotation
  double jaw_alignment_rad = 0;    // at the first touch
  std::int32_t object_drops = 0;
  // The knot-topology module's answers, copied for the score.
  std::int32_t answers = 0;
  std::int32_t wrong_answers = 0;
  double response_time_sum_s = 0;
  // The knot-placement module's stitches' errors (station/placement_module.h).
  std::int32_t stitches = 0;
  double spacing_error_rad = 0;
  double bite_error_m = 0;
  double shape_error_m = 0;  // nylon control (ThreadModuleState)
  // Knot tying: throws tied and pulled, and the knot the stitch-knot recogniser names in the
  // thread at the task's end (knot::StitchKnotType; -1 until recognised, off the haptic thread).
  std::int32_t throws_pulled = 0;
  std::int32_t tied_knot = -1;
  std::uint8_t bite_pulled_out = 0;  // the stitch has torn out of the tissue: the knot fails
  // Knot tying, in the hold after the last throw: the ends' pull against the scene's hold
  // tension, squared relative errors summed over both ends, and the samples (two per step).
  double tension_sq_sum = 0;
  std::uint64_t tension_samples = 0;
  // The needle through tissue (common/puncture), copied for the score; 1 m while the entry
  // (exit) has not been made.
  double entry_error_m = 1;
  double exit_error_m = 1;
  double peak_strain = 0;
  double torn_m = 0;  // also knot tying: how far the bite has cut through (KnotTieState)
  double off_circle_m = 0;
  std::int32_t punctures = 0;
  // This step.
  std::uint8_t fault = 0;
  double fault_value = 0;         // of the first module at fault (clearance, strain, force)
  std::int8_t contact_event = 0;  // +1 a fault episode began, -1 one ended
};
inline constexpr int kContactReleaseSteps = 50;
enum class TaskOutcome : std::uint8_t { kRunning = 0, kCompleted = 1, kTimeLimit = 2 };

// The needle–vessel module: the needle's pose and its clearance to the tube.
struct NeedleState {
  Eigen::Isometry3d X_WN = Eigen::Isometry3d::Identity();
  geometry::ArcTorusClearance clearance;
  double error_estimate_m = 0;  // |SP − sampled|, refreshed every kErrorCheckPeriod steps; NaN
  std::uint32_t warnings = 0;   // failed queries
};

// The tremor module: the running mean square of the band (about one second).
struct TremorState {
  double band_m = 0;  // |band-passed position| this step
  double mean_square_m2 = 0;
};

// Knot tying with the thread module: the throws chosen with the buttons, the throw under way
// (its script, a plain value) or the hold, and how much of each hand's deviation from its rest
// pose reaches the thread's ends (1 while they pull and hold, 0 while the instrument tie is
// guided; it ramps between the two).
struct KnotTieState {
  thread::KnotThrowScript script;  // the throw under way (done when none)
  thread::KnotHoldScript hold;     // the hold after the last throw
  thread::KnotTyingHands hands;    // grasp slots: who holds the standing and the working end
  std::int32_t chosen = 0;         // throws chosen so far
  std::int32_t started = 0;        // throws started
  std::int32_t pulled = 0;         // throws tied and pulled
  std::array<std::int8_t, 3> passes{};
  std::array<std::int8_t, 3> right{};
  std::uint32_t prev_buttons = 0;
  std::uint8_t holding = 0;
  std::uint8_t done = 0;  // the hold is over: the task's end
  double coupling = 1;    // of the hands' deviations, 0..1
  // The deviations applied at the last step, per grasp slot of the two ends (tool, second).
  Eigen::Vector3d applied_tool_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d applied_second_W = Eigen::Vector3d::Zero();
  // A stitch through the tissue module's patch: per rod (the first puncture, the bite, the
  // second puncture: thread::KnotStitchDef::Colliders),
  // the thread's load on it along the patch's normal (out of the tissue positive, N) at the
  // last step, and that load low-passed (knot_tying.stitch_relax_s), which the patch's
  // compliance turns into the rods' displacement and the tissue module into the patch's.
  std::array<double, 3> stitch_force_N{};
  std::array<double, 3> stitch_load_N{};
  // knot_tying.stitch_in_plane: the thread's load on each rod along the patch's surface,
  // low-passed alike, (x, y) of the patch's frame per rod, N.
  std::array<double, 6> stitch_in_plane_load_N{};
  // How far the bite has cut up through the tissue along the normal (knot_tying.bite_tear_N),
  // m, and whether it has been pulled out (the thread under it has reached the surface).
  double bite_cut_m = 0;
  std::uint8_t bite_pulled_out = 0;
};

// The suture-thread module.
struct ThreadModuleState {
  thread::ThreadState thread;
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();  // thread on the tool, saturated, N
  // Bimanual scenes: the thread on the second tool (which holds node 0), saturated, N.
  Eigen::Vector3d f_T2_W = Eigen::Vector3d::Zero();
  // Nylon control: the RMS distance of the nodes from the target shape after rigid alignment.
  double shape_error_m = 0;
  // Knot tying (task kind knot_tying; scene::KnotTyingSceneDef).
  KnotTieState tie;
};

// The tissue module.
struct TissueModuleState {
  fem::TissueState tissue;
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();  // tissue on the tool, N (unsaturated)
  puncture::PunctureState puncture;                 // tool: needle (the needle through it)
};

// The grasping module: the object, the jaws' contacts and the grasp's metrics.
struct GraspModuleState {
  grasp::GraspState grasp;
};

// The loop-along-a-wire module: the loop's clearance to the wire and its progress along it.
struct LoopModuleState {
  geometry::LoopWireClearance clearance;
  double s_m = 0;       // arc length of the wire-axis point nearest the loop's centre
  double offset_m = 0;  // the loop centre's distance from the wire's axis
  Eigen::Vector3d p_WA_centre = Eigen::Vector3d::Zero();  // that nearest wire-axis point
  std::uint32_t warnings = 0;                             // failed queries
};

// The knot-topology module: which knot is shown, since when, and the answers so far.
struct KnotQuizState {
  std::int32_t item = 0;     // the knot shown (index into the scene's items); = items: done
  double item_start_s = 0;   // when it appeared
  std::int32_t correct = 0;  // answers that named the knot shown
  double response_time_sum_s = 0;
  std::int32_t last_answer = 0;  // the class the last answer named (0: none yet)
  std::uint32_t prev_buttons = 0;
};

inline constexpr int kMaxStitches = 16;

// The knot-placement module: the stitches placed so far.
struct PlacementState {
  std::int32_t count = 0;
  std::array<double, kMaxStitches> azimuth_rad{};  // about the vessel axis, [0, 2π)
  std::array<double, kMaxStitches> bite_m{};       // below the cut edge
  std::uint32_t prev_buttons = 0;
};

struct StationState {
  std::uint64_t step = 0;  // steps taken; the next step has this index
  // The station's random numbers (SplitMix64; NextRandom). Seeded from the station's seed;
  // a module that draws random numbers draws them here, so a copy continues identically.
  std::uint64_t seed = 0;
  std::uint64_t rng = 0;
  ToolState tool;
  // The second tool, in the trainee's other hand: present exactly in bimanual scenes
  // (scene::SceneModel::second_hand). The cues act on the first tool only.
  std::optional<ToolState> second_tool;
  CueState cues;
  ScoreState score;
  // One section per module of the scene; empty when the scene does not name the module.
  std::optional<NeedleState> needle;
  std::optional<TremorState> tremor;
  std::optional<ThreadModuleState> thread;
  std::optional<TissueModuleState> tissue;
  std::optional<GraspModuleState> grasp;
  std::optional<LoopModuleState> loop;
  std::optional<KnotQuizState> knots;
  std::optional<PlacementState> placement;
};

// Seeds the generator (the sections are filled by the modules).
void SeedStationState(std::uint64_t seed, StationState& state);
// The next 64 random bits of the station's generator (SplitMix64: the same on every platform).
std::uint64_t NextRandom(StationState& state);

// Field by field, bit for bit (NaN equals the same NaN; 0.0 differs from −0.0): the equality
// that determinism means. Allocates (not for the haptic thread).
bool operator==(const StationState& a, const StationState& b);

}  // namespace microdex::state
