#pragma once
// The audio cues that are on, rendered step by step from the snapshots
// (common/cues/audio_synth.h) on the publisher thread:
// - AudioOut (--audio-out FILE.wav): the whole run, written as a WAV file at the end;
// - AudioBlockStream (--view: the station page's Web Audio): the same synthesis cut into
//   blocks (view_audio.h, 441 samples = 10 ms at 44.1 kHz by default), each stamped with the
//   step and tick stamp of its first sample and of the most recent audio cause, handed to a
//   sink (the view server's ring) while a page has asked for audio and some audio cue is on.
// The haptic thread never sees either.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/cues/audio_synth.h"
#include "common/view/view_audio.h"
#include "station/snapshot.h"

namespace microdex::station {

// The audio cues' inputs of one step.
cues::AudioCueFrame AudioCueFrameOf(const TickSnapshot& s);

// The cues with a sound: audio_click, audio_error, audio_proximity, audio_geiger and the
// predictive cue's warning beep.
inline constexpr std::uint32_t kAudioCueMask =
    cues::CueBit(cues::CueKind::kAudioClick) | cues::CueBit(cues::CueKind::kAudioError) |
    cues::CueBit(cues::CueKind::kAudioProximity) | cues::CueBit(cues::CueKind::kAudioGeiger) |
    cues::CueBit(cues::CueKind::kPredictive);

class AudioOut {
 public:
  AudioOut(double haptic_rate_hz, const cues::AudioSynthDef& def = {});
  // Renders the samples of one haptic step (44.1 at 44.1 kHz and 1 kHz: the fractions carry).
  void Add(const TickSnapshot& s);
  // Throws std::runtime_error naming the path when it cannot be written.
  void Write(const std::string& path) const;
  const std::vector<float>& samples() const { return samples_; }

 private:
  cues::AudioSynthDef def_;
  cues::AudioSynthState state_;
  double samples_per_step_;
  double carry_ = 0;
  std::vector<float> samples_;
};

class AudioBlockStream {
 public:
  // Takes a finished block; false when it could not (a full ring: the block is counted as
  // dropped). Called on the thread that calls Add.
  using Sink = std::function<bool(const view::AudioBlock&)>;

  // block_samples: 1..view::kMaxAudioBlockSamples. Throws std::invalid_argument naming the
  // bad argument.
  AudioBlockStream(double haptic_rate_hz, Sink sink, std::uint32_t block_samples = 441,
                   const cues::AudioSynthDef& def = {});
  // One step, in step order. wanted: some page has asked for audio. Nothing is rendered while
  // it is not wanted or no audio cue is on; the block in progress then goes out short with
  // kAudioEnd, and the next stream starts with kAudioStart and fresh oscillators. Allocates
  // nothing.
  void Add(const TickSnapshot& s, bool wanted);

  std::uint64_t blocks() const { return seq_; }
  std::uint64_t dropped() const { return dropped_; }

 private:
  void Emit(std::uint16_t flags);

  cues::AudioSynthDef def_;
  Sink sink_;
  std::uint32_t block_samples_;
  double samples_per_step_;
  cues::AudioSynthState state_;
  double carry_ = 0;
  std::vector<float> step_pcm_;  // one step's samples (sized once)
  view::AudioBlock block_;       // the block being filled
  bool streaming_ = false;
  bool block_open_ = false;
  cues::AudioCueFrame last_{};
  std::uint32_t last_audio_cues_ = 0;
  std::uint64_t cause_step_ = 0;
  double cause_stamp_ms_ = 0;
  std::uint32_t cause_ = 0;
  std::uint64_t seq_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace microdex::station
