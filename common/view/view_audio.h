#pragma once
// The station's audio cues as the page plays them: blocks of PCM that the station renders with
// the same synthesis as --audio-out (common/cues/audio_synth.h) on its publisher thread, sent
// to the pages that asked for audio ("audio on") as binary WebSocket messages of their own
// type, next to the state frames (view_frame.h). The layout is mirrored by
// common/view/src/audio_block.ts (README.md "Audio blocks"); kAudioVersion changes with it.
//
//   bytes 0..7    u32 magic "MDXA", u16 version, u16 flags (kAudioStart, kAudioEnd)
//   bytes 8..15   u32 sample rate (Hz), u32 sample count n
//   bytes 16..23  u64 block sequence number (one per block since the station started; a gap:
//                 blocks dropped on the way)
//   bytes 24..39  u64 step of the first sample, f64 its tick's stamp (CLOCK_REALTIME, ms)
//   bytes 40..55  u64 step of the most recent audio cause, f64 its tick's stamp (ms)
//   bytes 56..63  u32 what that cause was (kCause* bits), u32 audio cues on (1 << CueKind)
//   bytes 64..79  f32 the proximity tone's pitch (Hz; 0: silent), f32 the clearance (m; +inf:
//                 no wall), f32 the Geiger counter's mean rate (Hz; 0: silent), u32 the index
//                 of the cause step's first sample in this block (kCauseBefore: the cause came
//                 before this block)
//   bytes 80..87  f64 when the station's view server sent it (CLOCK_REALTIME, ms)
//   bytes 88..    n f32 samples in [−1, 1], mono
// The pitch, clearance and rate are those of the block's last step. Little-endian throughout.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace microdex::view {

inline constexpr std::uint32_t kAudioMagic = 0x4158444d;  // "MDXA" read as little-endian u32
inline constexpr std::uint16_t kAudioVersion = 1;
inline constexpr std::size_t kAudioHeaderBytes = 88;
inline constexpr std::size_t kMaxAudioBlockSamples = 1024;
inline constexpr std::size_t kMaxAudioBlockBytes = kAudioHeaderBytes + 4 * kMaxAudioBlockSamples;

// Flags.
inline constexpr std::uint16_t kAudioStart = 1;  // the first block after silence (a new stream)
inline constexpr std::uint16_t kAudioEnd = 2;    // the last block: no audio cue on any more

// Causes: what changed in the audio cues' inputs at the cause step.
inline constexpr std::uint32_t kCauseClick = 1;      // a contact began (audio_click)
inline constexpr std::uint32_t kCauseError = 2;      // the fault began or ended (audio_error)
inline constexpr std::uint32_t kCauseWarning = 4;    // the predictive warning began or ended
inline constexpr std::uint32_t kCauseProximity = 8;  // the tone's pitch changed (the clearance)
inline constexpr std::uint32_t kCauseGeiger = 16;    // the Geiger counter's rate changed
inline constexpr std::uint32_t kCauseCueOn = 32;     // an audio cue was switched on or off

inline constexpr std::uint32_t kCauseBefore = 0xffffffff;

// One block, plain data (it travels through an SpscRing).
struct AudioBlock {
  std::uint16_t flags = 0;
  std::uint32_t sample_rate_hz = 0;
  std::uint32_t samples = 0;
  std::uint64_t seq = 0;
  std::uint64_t first_step = 0;
  double first_stamp_ms = 0;
  std::uint64_t cause_step = 0;
  double cause_stamp_ms = 0;
  std::uint32_t cause = 0;
  std::uint32_t active_cues = 0;
  float tone_hz = 0;
  float clearance_m = 0;
  float geiger_rate_hz = 0;
  std::uint32_t cause_offset = kCauseBefore;
  double sent_ms = 0;
  std::array<float, kMaxAudioBlockSamples> pcm{};
};

// The message bytes of a block (samples beyond kMaxAudioBlockSamples are cut).
std::string EncodeAudioBlock(const AudioBlock& block);
// The inverse; throws std::invalid_argument("audio block: reason") for a message that is not
// one (short, foreign magic or version, a sample count that disagrees with the length, a sample
// rate outside 8 kHz..192 kHz, a cause offset beyond the samples, samples that are not numbers
// in [−1, 1]).
AudioBlock DecodeAudioBlock(const void* data, std::size_t size);

}  // namespace microdex::view
