#pragma once
// The binary state frame the view pages draw from (WebSocket, one frame a message), encoded
// from the mirrored states (common/net's plain types), the same for the station's page and
// each tile of the instructor's console. The layout is mirrored by common/view/src/frame.ts
// (README.md "Frames"); kFrameVersion changes with it.
//
//   bytes 0..15   header: u32 magic "MDXF", u16 version, u16 flags (bit per section present),
//                 u32 station slot (console: index in its station list; station: 0),
//                 u32 thread node count
//   bytes 16..    kScalarCount float64 scalars (index names below)
//   then          float32 thread nodes (x, y, z per node, world, m), then float32 tissue
//                 displacement field (nodes_x * nodes_y, x fastest, m), then the cue overlay
//                 (common/cues/cue_overlay.h) as float32: polyline count, label count; per
//                 polyline role, r, g, b, a, width (m), point count, then x, y, z per point;
//                 per label role, r, g, b, a, x, y, z, then 32 bytes of text (NUL-padded)
// Little-endian throughout (x86-64 and every browser's typed arrays on it).
// The other binary message on the station's WebSocket, its audio cue blocks (magic "MDXA"), is
// laid out in view_audio.h.

#include <array>
#include <cstddef>
#include <cstdint>

#include "common/cues/cue_overlay.h"
#include "common/net/messages.h"

namespace microdex::view {

inline constexpr std::uint32_t kFrameMagic = 0x4658444d;  // "MDXF" read as little-endian u32
inline constexpr std::uint16_t kFrameVersion = 4;
inline constexpr std::size_t kFrameHeaderBytes = 16;

// Section flags.
inline constexpr std::uint16_t kHasNeedle = 1;
inline constexpr std::uint16_t kHasThread = 2;
inline constexpr std::uint16_t kHasTissue = 4;
inline constexpr std::uint16_t kHasScore = 8;
inline constexpr std::uint16_t kHasTelemetry = 16;
inline constexpr std::uint16_t kHasOverlay = 32;
inline constexpr std::uint16_t kHasSecondTool = 64;

// Scalar indices (float64).
enum Scalar : int {
  kStampMs = 0,      // tick start of the tool state, CLOCK_REALTIME, ms
  kStep = 1,         // its haptic step
  kSentMs = 2,       // when the frame was encoded, CLOCK_REALTIME, ms
  kToolP = 3,        // p_WT x, y, z (m)
  kToolQ = 6,        // q_WT w, x, y, z
  kToolForce = 10,   // f_T_W x, y, z (N)
  kActiveCues = 13,  // bit (1 << cues::CueKind)
  kTremorRms = 14,   // m
  kNeedleP = 15,     // p_WN x, y, z
  kNeedleQ = 18,     // q_WN w, x, y, z
  kClearance = 22,   // m
  kContact = 23,     // 0 / 1
  kThreadStrain = 24,
  kGraspedNode = 25,
  kTissueNodesX = 26,
  kTissueNodesY = 27,
  kTissueDepth = 28,  // largest |w|, m
  kTissueP = 29,      // p_WS x, y, z
  kTissueQ = 32,      // q_WS w, x, y, z
  kTissueLx = 36,
  kTissueLy = 37,
  kScore = 38,
  kProgress = 39,
  kOutcome = 40,        // state::TaskOutcome: 0 running, 1 completed, 2 time limit
  kPeriodP99Ms = 41,    // haptic period p99 of the last telemetry window
  kOverruns = 42,       // in that window
  kPresence = 43,       // console: 0 alive, 1 lost, 2 departed
  kToolAgeMs = 44,      // console: age of the mirrored tool state when encoded
  kTool2P = 48,         // bimanual: the second tool's p_WT x, y, z (m)
  kTool2Q = 51,         // its q_WT w, x, y, z
  kTool2Force = 55,     // the force sent to it, x, y, z (N)
  kStitchCount = 58,    // knot placement: the stitches placed so far (0..16)
  kStitchAzimuth = 59,  // their azimuths about the vessel axis, rad (16 slots)
  kStitchBite = 75,     // their bites below the cut edge, m (16 slots)
  kScalarCount = 91,
};

inline constexpr std::size_t kMaxFrameThreadNodes = net::kMaxThreadNodes;
inline constexpr std::size_t kMaxFrameTissueNodes = net::kMaxTissueNodes;
inline constexpr std::size_t kOverlayLabelBytes = 32;
inline constexpr std::size_t kMaxOverlayBytes =
    4 * (2 + cues::kMaxOverlayPolylines * (7 + 3 * cues::kMaxOverlayPoints) +
         cues::kMaxOverlayLabels * 8) +
    cues::kMaxOverlayLabels * kOverlayLabelBytes;
inline constexpr std::size_t kMaxFrameBytes = kFrameHeaderBytes + kScalarCount * 8 +
                                              kMaxFrameThreadNodes * 3 * 4 +
                                              kMaxFrameTissueNodes * 4 + kMaxOverlayBytes;

// One encoded frame, plain data (it travels through a TripleBuffer).
struct FrameBytes {
  std::uint32_t size = 0;
  std::array<std::uint8_t, kMaxFrameBytes> bytes{};
};

// The mirrored states a frame is made of; null pointers are sections not present.
struct FrameSource {
  std::uint32_t slot = 0;
  const net::ToolState* tool = nullptr;  // required
  const net::NeedleState* needle = nullptr;
  const net::ThreadState* thread = nullptr;
  const net::TissueState* tissue = nullptr;
  const net::Score* score = nullptr;
  const net::Telemetry* telemetry = nullptr;
  const cues::CueOverlay* overlay = nullptr;
  double presence = 0;
  double tool_age_ms = 0;
  std::int64_t sent_realtime_ns = 0;
};

// Encodes `source` into `out` (never allocates). Sections longer than the bounds are cut.
void EncodeFrame(const FrameSource& source, FrameBytes& out);

}  // namespace microdex::view
