#include "station/audio_out.h"

#include <cmath>
#include <span>
#include <stdexcept>

namespace microdex::station {

cues::AudioCueFrame AudioCueFrameOf(const TickSnapshot& s) {
  cues::AudioCueFrame f;
  f.active = s.active_cues;
  f.param = s.cue.param;
  f.clearance_m = s.cue.clearance_m;
  f.click = s.cue.click != 0;
  f.error = s.cue.error != 0;
  f.warning = s.cue.warning != 0;
  return f;
}

AudioOut::AudioOut(double haptic_rate_hz, const cues::AudioSynthDef& def)
    : def_(def), samples_per_step_(def.sample_rate_hz / haptic_rate_hz) {
  def_.Validate();
}

void AudioOut::Add(const TickSnapshot& s) {
  const cues::AudioCueFrame f = AudioCueFrameOf(s);
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

namespace {

// The proximity of a distance cue that is on (0 when off or out of range).
double ProximityOf(const cues::AudioCueFrame& f, cues::CueKind kind) {
  if ((f.active & cues::CueBit(kind)) == 0) return 0;
  return cues::CalcProximity(f.clearance_m, f.param[static_cast<std::size_t>(kind)]);
}

}  // namespace

AudioBlockStream::AudioBlockStream(double haptic_rate_hz, Sink sink, std::uint32_t block_samples,
                                   const cues::AudioSynthDef& def)
    : def_(def),
      sink_(std::move(sink)),
      block_samples_(block_samples),
      samples_per_step_(def.sample_rate_hz / haptic_rate_hz) {
  def_.Validate();
  if (!(haptic_rate_hz > 0) || !std::isfinite(haptic_rate_hz)) {
    throw std::invalid_argument("haptic_rate_hz: expected a positive number");
  }
  if (block_samples < 1 || block_samples > view::kMaxAudioBlockSamples) {
    throw std::invalid_argument("block_samples: expected 1.." +
                                std::to_string(view::kMaxAudioBlockSamples));
  }
  if (!sink_) throw std::invalid_argument("sink: expected a function");
  step_pcm_.resize(static_cast<std::size_t>(std::ceil(samples_per_step_)) + 1);
}

void AudioBlockStream::Emit(std::uint16_t flags) {
  block_.flags |= flags;
  block_.seq = seq_++;
  block_.cause_step = cause_step_;
  block_.cause_stamp_ms = cause_stamp_ms_;
  block_.cause = cause_;
  if (block_.cause_offset != view::kCauseBefore && block_.cause_step < block_.first_step) {
    block_.cause_offset = view::kCauseBefore;
  }
  if (!sink_(block_)) ++dropped_;
  block_open_ = false;
}

void AudioBlockStream::Add(const TickSnapshot& s, bool wanted) {
  const std::uint32_t audio_cues = s.active_cues & kAudioCueMask;
  if (!wanted || audio_cues == 0) {
    if (block_open_) Emit(view::kAudioEnd);
    streaming_ = false;
    return;
  }
  const cues::AudioCueFrame f = AudioCueFrameOf(s);
  const double x_tone = ProximityOf(f, cues::CueKind::kAudioProximity);
  const double x_geiger = ProximityOf(f, cues::CueKind::kAudioGeiger);
  // What changed at this step that the sound follows.
  std::uint32_t cause = 0;
  const bool start = !streaming_;
  if (start) {
    state_ = {};
    carry_ = 0;
    cause |= view::kCauseCueOn;
  } else {
    if (audio_cues != last_audio_cues_) cause |= view::kCauseCueOn;
    if (ProximityOf(last_, cues::CueKind::kAudioProximity) != x_tone) {
      cause |= view::kCauseProximity;
    }
    if (ProximityOf(last_, cues::CueKind::kAudioGeiger) != x_geiger) cause |= view::kCauseGeiger;
    if ((f.active & cues::CueBit(cues::CueKind::kAudioError)) != 0 && f.error != last_.error) {
      cause |= view::kCauseError;
    }
    if ((f.active & cues::CueBit(cues::CueKind::kPredictive)) != 0 && f.warning != last_.warning) {
      cause |= view::kCauseWarning;
    }
  }
  if ((f.active & cues::CueBit(cues::CueKind::kAudioClick)) != 0 && f.click) {
    cause |= view::kCauseClick;
  }
  const double stamp_ms = static_cast<double>(s.stamp_ns) * 1e-6;
  if (cause != 0) {
    cause_step_ = s.step;
    cause_stamp_ms_ = stamp_ms;
    cause_ = cause;
  }
  streaming_ = true;
  last_ = f;
  last_audio_cues_ = audio_cues;

  carry_ += samples_per_step_;
  const auto n = static_cast<std::size_t>(std::floor(carry_));
  carry_ -= static_cast<double>(n);
  const std::span<float> pcm(step_pcm_.data(), n);
  cues::SynthesizeAudio(def_, f, state_, pcm);
  for (std::size_t i = 0; i < n;) {
    if (!block_open_) {
      block_.flags = start && i == 0 ? view::kAudioStart : 0;
      block_.sample_rate_hz = static_cast<std::uint32_t>(std::lround(def_.sample_rate_hz));
      block_.samples = 0;
      block_.first_step = s.step;
      block_.first_stamp_ms = stamp_ms;
      block_.cause_offset = view::kCauseBefore;
      block_open_ = true;
    }
    if (cause != 0 && i == 0) block_.cause_offset = block_.samples;
    const std::size_t take = std::min<std::size_t>(n - i, block_samples_ - block_.samples);
    std::copy_n(pcm.begin() + static_cast<std::ptrdiff_t>(i), take,
                block_.pcm.begin() + block_.samples);
    block_.samples += static_cast<std::uint32_t>(take);
    i += take;
    block_.active_cues = audio_cues;
    block_.tone_hz = x_tone > 0 ? static_cast<float>(cues::CalcToneHz(def_, x_tone)) : 0.0f;
    block_.clearance_m = static_cast<float>(f.clearance_m);
    block_.geiger_rate_hz =
        x_geiger > 0 ? static_cast<float>(cues::CalcGeigerRateHz(def_, x_geiger)) : 0.0f;
    if (block_.samples == block_samples_) Emit(0);
  }
}

}  // namespace microdex::station
