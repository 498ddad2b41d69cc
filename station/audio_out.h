#pragma once
// --audio-out FILE.wav: the audio cues that are on, rendered step by step from the snapshots
// (common/cues/audio_synth.h) on the publisher thread and written as a WAV file at the end.
// The same synthesis feeds a live output (the station page's Web Audio); a file makes it
// testable and reviewable.

#include <cstdint>
#include <string>
#include <vector>

#include "common/cues/audio_synth.h"
#include "station/snapshot.h"

namespace microdex::station {

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

}  // namespace microdex::station
