#pragma once
// What the haptic thread hands to the publisher thread after every step (through the
// snapshot ring): a projection of the station's state (ProjectSnapshot) plus the step's
// timing, and the large frames of the thread and tissue once per mirror period. Plain,
// fixed-size, trivially copyable: copying one never allocates. The conversion to the DDS
// messages lives in the publisher (common/net's plain types), not here.

#include <array>
#include <cstdint>

#include "common/state/station_state.h"
#include "station/rt/triple_buffer.h"

namespace microdex::station {

inline constexpr int kMaxStationModules = 8;
// Frame bounds: those of the DDS types (the publisher checks they agree).
inline constexpr std::size_t kMaxFrameThreadNodes = 512;
inline constexpr std::size_t kMaxFrameTissueNodes = 16384;

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // (w, x, y, z)

struct ModuleSample {
  double step_time_s = 0;      // wall time of this module's step (telemetry, not state)
  double error_estimate = 0;   // module-defined; NaN when none
  std::uint32_t warnings = 0;  // running count
};

struct NeedleSnapshot {
  Vec3 p_WN{};
  Quat q_WN{1, 0, 0, 0};
  double clearance_m = 0;
  std::uint8_t contact = 0;
  geometry::ClearanceStatus status = geometry::ClearanceStatus::kOk;
  double s_rad = 0;
  Vec3 p_WD{};
  Vec3 p_WB{};
};

// The thread module's mirrored state, written by the haptic thread every mirror period.
struct ThreadFrame {
  std::uint64_t step = 0;
  std::int64_t stamp_ns = 0;
  int num_nodes = 0;
  std::array<Vec3, kMaxFrameThreadNodes> p_W{};  // node positions, world, m
  double max_strain = 0;
  int grasped_node = -1;
  Vec3 f_T_W{};  // thread on the tool, N
};

// The tissue module's mirrored state: the displacement field on the display grid.
struct TissueFrame {
  std::uint64_t step = 0;
  std::int64_t stamp_ns = 0;
  std::uint32_t nodes_x = 0;
  std::uint32_t nodes_y = 0;
  std::uint32_t mesh_revision = 0;
  std::uint32_t unknowns = 0;
  double max_displacement_m = 0;
  fem::TissueStatus status = fem::TissueStatus::kNoContact;
  std::array<float, kMaxFrameTissueNodes> w_m{};  // x fastest
};

// Large states go through latest-value handoffs rather than the per-step snapshot ring (a
// ring of 4096 tissue fields would need 256 MiB); only the module that owns one writes it.
struct LargeFrames {
  rt::TripleBuffer<ThreadFrame> thread;  // producer: haptic thread; consumer: publisher thread
  rt::TripleBuffer<TissueFrame> tissue;  // producer: haptic thread; consumer: publisher thread
};

// The cue signals after a step (state::CueState): what the overlay and the audio render.
struct CueSnapshot {
  std::array<double, cues::kCueKindCount> param{};
  double clearance_m = 0;
  double deviation_m = 0;
  Vec3 p_W_nearest{};
  std::uint8_t click = 0;
  std::uint8_t error = 0;
  std::uint8_t prediction_valid = 0;
  std::uint8_t warning = 0;
  Vec3 p_W_end{};
  double prediction_error_m = 0;
  std::uint8_t has_wall_points = 0;
  Vec3 p_W_tool_near{};
  Vec3 p_W_wall{};
};

// Bimanual scenes: the second tool after a step (state.second_tool; no cue acts on it, so the
// tool is the device's pose).
struct SecondToolSnapshot {
  Vec3 p_WT_device{};
  Quat q_WT_device{1, 0, 0, 0};
  double gripper = 0;
  std::uint32_t buttons = 0;
  Vec3 f_T_W{};
  std::uint8_t device_fault = 0;
};

struct TickSnapshot {
  std::uint64_t step = 0;
  std::int64_t tick_start_ns = 0;  // monotonic
  std::int64_t stamp_ns = 0;       // CLOCK_REALTIME at tick start
  std::int64_t period_ns = 0;      // since the previous tick start
  std::uint8_t overrun = 0;        // started more than one period after its deadline
  // Device, raw.
  Vec3 p_WT_device{};
  Quat q_WT_device{1, 0, 0, 0};
  double gripper = 0;
  std::uint32_t buttons = 0;
  // Tool after cues, and the force sent to the device.
  Vec3 p_WT{};
  Quat q_WT{1, 0, 0, 0};
  Vec3 f_T_W{};
  std::uint32_t active_cues = 0;  // bit cues::CueBit(kind) per cue on
  CueSnapshot cue;
  std::uint8_t has_second_tool = 0;
  SecondToolSnapshot second;
  // Modules (filled by the modules present).
  std::uint8_t has_needle = 0;
  NeedleSnapshot needle;
  std::uint8_t has_tremor = 0;
  double tremor_band_m = 0;  // |band-passed position| this step
  double tremor_rms_m = 0;
  std::array<ModuleSample, kMaxStationModules> modules{};
  int module_count = 0;
  // Events of this step.
  std::array<state::CueAck, state::kMaxAcksPerStep> acks{};
  int ack_count = 0;
  // A fault this step: needle contact with the wall, thread overstretched, tissue pressed too
  // hard. Fault episodes are the score's "contacts".
  std::uint8_t fault = 0;
  double fault_value = 0;            // of the first module at fault (clearance, strain, force)
  std::int8_t contact_event = 0;     // +1 fault episode began, -1 ended
  std::uint32_t force_warnings = 0;  // running count of non-finite forces replaced by zero
  std::uint8_t device_fault = 0;     // station::DeviceFault of this step
  std::uint64_t state_hash = 0;      // CalcStateHash after this step, when has_state_hash
  std::uint8_t has_state_hash = 0;
  std::uint64_t step_hash = 0;  // CalcStateHash after this step, every step (DeviceInput)
  state::ScoreState score;
  // Knot placement: the stitches placed so far (state.placement).
  int stitch_count = 0;
  std::array<float, state::kMaxStitches> stitch_azimuth_rad{};
  std::array<float, state::kMaxStitches> stitch_bite_m{};
};

}  // namespace microdex::station
