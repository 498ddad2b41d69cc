#pragma once
// Plain C++ views of the DDS samples (idl/*.idl), in SI units with frames in the names.
// Physics, the station and the instructor use these; only common/net sees microdex::msg.
// Bounds (kMax...) are those of the IDL; FromMsg rejects a sample that exceeds them.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/cues/cue_kind.h"

namespace microdex::net {

inline constexpr std::size_t kMaxIdLength = 64;  // station_id, session_id
inline constexpr std::size_t kMaxModules = 16;   // StationInfo.modules
inline constexpr std::size_t kMaxModuleNameLength = 32;
inline constexpr std::size_t kMaxThreadNodes = 512;    // ThreadState.nodes
inline constexpr std::size_t kMaxTissueNodes = 16384;  // TissueState.displacement_m
inline constexpr std::size_t kMaxTelemetryModules = 16;
inline constexpr std::size_t kMaxStitches = 16;     // ToolState.stitch_* (state::kMaxStitches)
inline constexpr const char* kAllStations = "all";  // CueCommand target for every station

// Fields every sample carries.
struct Header {
  std::string station_id;  // the key
  std::string session_id;
  std::uint64_t step = 0;     // haptic step index
  std::int64_t stamp_ns = 0;  // source time, CLOCK_REALTIME, ns
};

struct StationInfo {
  Header header;
  std::string trainee;
  std::string scene;
  std::vector<std::string> modules;
  std::string build;
  double haptic_rate_hz = 0;
  double mirror_rate_hz = 0;
  double skill = -1;  // simulated trainee skill 0..1; -1: a real device
  std::string device;
  std::uint64_t seed = 0;        // the simulation's seed
  std::uint64_t scene_hash = 0;  // of the scene's files (SceneDescription); 0: none sent
};

struct DeviceInput {
  Header header;
  Eigen::Vector3d p_WT = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WT = Eigen::Quaterniond::Identity();
  double gripper = 0;
  std::uint32_t buttons = 0;
  std::uint64_t state_hash = 0;  // of the station's state after this step
  // Bimanual scenes: the second tool's device sample (idl/device_input.idl).
  Eigen::Vector3d p_WT2 = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WT2 = Eigen::Quaterniond::Identity();
  double gripper2 = 0;
  std::uint32_t buttons2 = 0;
};

struct ToolState {
  Header header;
  Eigen::Vector3d p_WT = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WT = Eigen::Quaterniond::Identity();
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();  // N
  double tremor_rms_m = 0;
  std::uint32_t active_cues =
      0;  // bit (1 << cues::CueKind); on the wire, bit (1 << msg::CueKind) of the same name
  // Bimanual scenes: the second tool (its device's pose) and the force sent to it.
  bool has_second_tool = false;
  Eigen::Vector3d p_WT2 = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WT2 = Eigen::Quaterniond::Identity();
  Eigen::Vector3d f_T2_W = Eigen::Vector3d::Zero();
  // Knot placement: the stitches placed so far (the others: 0).
  int stitch_count = 0;
  std::array<float, kMaxStitches> stitch_azimuth_rad{};  // [0, 2π)
  std::array<float, kMaxStitches> stitch_bite_m{};       // below the cut edge, m
};

enum class ClearanceStatus : std::uint8_t { kOk = 0, kEmptyRange = 1, kInvalidInput = 2 };

struct NeedleState {
  Header header;
  Eigen::Vector3d p_WN = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WN = Eigen::Quaterniond::Identity();
  double clearance_m = 0;
  bool contact = false;
  double s_rad = 0;
  Eigen::Vector3d p_WD = Eigen::Vector3d::Zero();  // deepest needle point
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();  // nearest wall point
  ClearanceStatus status = ClearanceStatus::kOk;
};

struct ThreadState {
  Header header;
  std::vector<Eigen::Vector3d> nodes;               // world, m; at most kMaxThreadNodes
  std::string knot;                                 // "" while not recognised yet
  double max_strain = 0;                            // max |l − r| / r over the links
  std::int32_t grasped_node = -1;                   // -1: none
  Eigen::Vector3d f_T_W = Eigen::Vector3d::Zero();  // thread on the tool, N
};

// The tissue step's status (fem::TissueStatus, enumerator for enumerator).
enum class TissueStepStatus : std::uint8_t {
  kOk,
  kNoContact,
  kBadInput,
  kTooManyContacts,
  kNotConverged,
  kFactorisationFailed,
  kNonFinite,
};

struct TissueState {
  Header header;
  Eigen::Vector3d p_WS = Eigen::Vector3d::Zero();  // patch corner in world
  Eigen::Quaterniond q_WS = Eigen::Quaterniond::Identity();
  double length_x_m = 0;
  double length_y_m = 0;
  std::uint32_t nodes_x = 0;  // display grid; displacement_m.size() == nodes_x * nodes_y
  std::uint32_t nodes_y = 0;
  std::uint32_t mesh_revision = 0;
  std::uint32_t unknowns = 0;
  double max_displacement_m = 0;
  TissueStepStatus status = TissueStepStatus::kOk;
  std::vector<float> displacement_m;  // x fastest; at most kMaxTissueNodes
};

struct ModuleTelemetry {
  std::string name;
  double step_time_mean_s = 0;
  double step_time_max_s = 0;
  double error_estimate = 0;
  std::string error_kind;
  std::uint32_t warnings = 0;
};

struct Telemetry {
  Header header;
  double window_s = 0;
  std::uint64_t ticks = 0;
  double period_mean_s = 0;
  double period_p99_s = 0;
  double period_max_s = 0;
  std::uint64_t overruns = 0;
  std::uint64_t ring_dropped = 0;
  bool realtime = false;
  std::vector<ModuleTelemetry> modules;
  // The latest state hash and the step after which it was taken (has_state_hash false until
  // the first).
  bool has_state_hash = false;
  std::uint64_t state_hash_step = 0;
  std::uint64_t state_hash = 0;
  // Invalid samples the station received and dropped, totals: cue commands, device bridge
  // samples.
  std::uint64_t cues_invalid = 0;
  std::uint64_t device_samples_invalid = 0;
};

struct CueCommand {
  Header header;  // station_id: the target station or kAllStations; step: 0 = on receipt
  std::uint64_t cue_id = 0;
  cues::CueKind kind = cues::CueKind::kClear;
  double param = 0;  // the kind's parameter (common/cues/cue_kind.h); unused when off
  std::string issuer;
  bool off = false;  // switch the kind off
  // A trial's condition: for the station's run of this session id only ("": any run), one of
  // condition_size commands (0: a cue on its own; at most kMaxConditionSize).
  std::string station_session;
  std::uint32_t condition_size = 0;
};
inline constexpr std::uint32_t kMaxConditionSize = 16;

enum class TaskEventKind : std::uint32_t {
  kTaskStart = 0,
  kTaskEnd = 1,
  kCueApplied = 2,
  kCueRejected = 3,
  kContactBegin = 4,
  kContactEnd = 5,
  kDeviceFault = 6,
  kDeviceOk = 7,
};
const char* TaskEventKindName(TaskEventKind kind);

struct TaskEvent {
  Header header;  // step: when it happened (for a cue: the step it was applied at)
  TaskEventKind kind = TaskEventKind::kTaskStart;
  std::uint64_t cue_id = 0;
  double value = 0;
  std::string text;
};

inline constexpr std::size_t kMaxScoreTerms = 12;

// A term of the score (station/score.h).
struct ScoreTerm {
  std::string metric;
  double value = 0;
  double limit = 1;
  double weight = 0;
  double points = 0;  // weight · clamp(1 − value / limit, 0, 1)
};

struct Score {
  Header header;
  bool is_final = false;
  double duration_s = 0;
  double time_in_contact_s = 0;
  std::uint32_t contacts = 0;
  double mean_clearance_m = 0;
  double min_clearance_m = 0;
  double path_length_m = 0;
  double ideal_path_length_m = 0;
  double tremor_rms_m = 0;
  double score = 0;
  std::string task;          // scene::TaskKindName
  std::uint8_t outcome = 0;  // state::TaskOutcome
  double deviation_mean_m = 0;
  double progress = 0;  // of the whole task, 0..1
  std::vector<ScoreTerm> terms;
};

}  // namespace microdex::net
