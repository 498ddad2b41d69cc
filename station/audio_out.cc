#include "station/audio_out.h"

#include <cmath>
#include <span>

namespace microdex::station {

AudioOut::AudioOut(double haptic_rate_hz, const cues::AudioSynthDef& def)
    : def_(def), samples_per_step_(def.sample_rate_hz / haptic_rate_hz) {
  def_.Validate();
}

void AudioOut::Add(const TickSnapshot& s) {
  cues::AudioCueFrame f;
  f.active = s.active_cues;
  f.param = s.cue.param;
  f.clearance_m = s.cue.clearance_m;
  f.click = s.cue.click != 0;
  f.error = s.cue.error != 0;
  f.warning = s.cue.warning != 0;
  carry_ += samples_per_step_;
  const auto n = static_cast<std::size_t>(std::floor(carry_));
  carry_ -= static_cast<double>(n);
  const std::size_t at = samples_.size();
  samples_.resize(at + n);
  cues::SynthesizeAudio(def_, f, state_, std::span<float>(samples_.data() + at, n));
}

void AudioOut::Write(const std::string& path) const {
  cues::WriteWav(path, samples_, static_cast<int>(std::lround(def_.sample_rate_hz)));
}

}  // namespace microdex::station
