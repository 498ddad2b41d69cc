#include "common/cues/audio_synth.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace microdex::cues {
namespace {

constexpr double kTwoPi = 2 * 3.14159265358979323846;

// A uniform number in [0, 1) (SplitMix64).
double NextUniform(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

double Wrap(double phase) { return phase >= 1 ? phase - std::floor(phase) : phase; }

void PutU32(std::ofstream& f, std::uint32_t v) {
  const unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                              static_cast<unsigned char>(v >> 16),
                              static_cast<unsigned char>(v >> 24)};
  f.write(reinterpret_cast<const char*>(b), 4);
}
void PutU16(std::ofstream& f, std::uint16_t v) {
  const unsigned char b[2] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8)};
  f.write(reinterpret_cast<const char*>(b), 2);
}
std::uint32_t GetU32(const unsigned char* b) {
  return b[0] | (b[1] << 8) | (b[2] << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
}

}  // namespace

void AudioSynthDef::Validate() const {
  if (!(sample_rate_hz >= 8000 && sample_rate_hz <= 192000)) {
    throw std::invalid_argument("sample_rate_hz: expected 8000..192000");
  }
  if (!(tone_low_hz > 0 && tone_low_hz < tone_high_hz && tone_high_hz < sample_rate_hz / 2)) {
    throw std::invalid_argument("tone_low_hz: expected 0 < low < high < Nyquist");
  }
  if (!(geiger_min_rate_hz > 0 && geiger_min_rate_hz < geiger_max_rate_hz)) {
    throw std::invalid_argument("geiger_min_rate_hz: expected 0 < min < max");
  }
}

double CalcProximity(double clearance_m, double range_m) {
  if (std::isnan(clearance_m) || !(range_m > 0)) return 0;
  return std::clamp(1 - clearance_m / range_m, 0.0, 1.0);
}

double CalcToneHz(const AudioSynthDef& def, double x) {
  return def.tone_low_hz * std::pow(def.tone_high_hz / def.tone_low_hz, x);
}

double CalcToneAmplitude(const AudioSynthDef& def, double x) {
  return def.tone_min_amplitude + (def.tone_max_amplitude - def.tone_min_amplitude) * x;
}

double CalcGeigerRateHz(const AudioSynthDef& def, double x) {
  return def.geiger_min_rate_hz * std::pow(def.geiger_max_rate_hz / def.geiger_min_rate_hz, x);
}

void SynthesizeAudio(const AudioSynthDef& def, const AudioCueFrame& f, AudioSynthState& s,
                     std::span<float> out) {
  const auto on = [&](CueKind k) { return (f.active & CueBit(k)) != 0; };
  const auto param = [&](CueKind k) { return f.param[static_cast<std::size_t>(k)]; };
  const double dt = 1 / def.sample_rate_hz;
  // audio_proximity: sounds while the clearance is below its range.
  const double x_tone = on(CueKind::kAudioProximity)
                            ? CalcProximity(f.clearance_m, param(CueKind::kAudioProximity))
                            : 0.0;
  const bool tone = x_tone > 0;
  const double tone_hz = CalcToneHz(def, x_tone);
  const double tone_amp = CalcToneAmplitude(def, x_tone);
  const double x_geiger =
      on(CueKind::kAudioGeiger) ? CalcProximity(f.clearance_m, param(CueKind::kAudioGeiger)) : 0.0;
  const bool geiger = x_geiger > 0;
  const double geiger_rate = CalcGeigerRateHz(def, x_geiger);
  const bool error = on(CueKind::kAudioError) && f.error;
  const bool warning = on(CueKind::kPredictive) && f.warning;
  if (on(CueKind::kAudioClick) && f.click) {
    s.click_age_s = 0;
    s.click_gain = param(CueKind::kAudioClick);
    s.click_tau_s = def.click_s;
  }
  for (float& y : out) {
    double v = 0;
    if (tone) {
      v += tone_amp * std::sin(kTwoPi * s.tone_phase);
      s.tone_phase = Wrap(s.tone_phase + tone_hz * dt);
    }
    if (geiger) {
      // Click intervals uniform in [0.5, 1.5] / rate: mean 1 / rate, less jitter than Poisson.
      s.geiger_wait_s -= dt;
      if (s.geiger_wait_s <= 0) {
        s.click_age_s = 0;
        s.click_gain = 0.8;
        s.click_tau_s = def.geiger_click_s;
        s.geiger_wait_s += (0.5 + NextUniform(s.rng)) / geiger_rate;
        if (s.geiger_wait_s < 0) s.geiger_wait_s = 0;
      }
    }
    if (s.click_age_s < 8 * s.click_tau_s) {
      v += s.click_gain * std::exp(-s.click_age_s / s.click_tau_s) *
           std::sin(kTwoPi * def.click_hz * s.click_age_s);
    }
    s.click_age_s += dt;
    if (error) {
      const double gate = s.beep_phase < 0.5 ? 1.0 : 0.0;
      v += gate * param(CueKind::kAudioError) * (s.error_phase < 0.5 ? 0.5 : -0.5);
      s.error_phase = Wrap(s.error_phase + def.error_hz * dt);
      s.beep_phase = Wrap(s.beep_phase + def.error_beep_hz * dt);
    }
    if (warning) {
      const double gate = s.beep_phase < 0.5 ? 1.0 : 0.0;
      v += gate * 0.3 * std::sin(kTwoPi * s.warning_phase);
      s.warning_phase = Wrap(s.warning_phase + def.warning_hz * dt);
      if (!error) s.beep_phase = Wrap(s.beep_phase + 2 * def.error_beep_hz * dt);
    }
    y = static_cast<float>(std::clamp(v, -1.0, 1.0));
  }
}

void WriteWav(const std::string& path, std::span<const float> samples, int sample_rate_hz) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot write");
  const auto data_bytes = static_cast<std::uint32_t>(samples.size() * 2);
  f.write("RIFF", 4);
  PutU32(f, 36 + data_bytes);
  f.write("WAVEfmt ", 8);
  PutU32(f, 16);  // PCM format chunk
  PutU16(f, 1);   // PCM
  PutU16(f, 1);   // mono
  PutU32(f, static_cast<std::uint32_t>(sample_rate_hz));
  PutU32(f, static_cast<std::uint32_t>(sample_rate_hz) * 2);  // bytes per second
  PutU16(f, 2);                                               // block align
  PutU16(f, 16);                                              // bits per sample
  f.write("data", 4);
  PutU32(f, data_bytes);
  for (float x : samples) {
    const double c = std::clamp(static_cast<double>(x), -1.0, 1.0);
    PutU16(f, static_cast<std::uint16_t>(static_cast<std::int16_t>(std::lround(c * 32767))));
  }
  if (!f) throw std::runtime_error(path + ": write failed");
}

std::vector<float> ReadWav(const std::string& path, int* sample_rate_hz) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot read");
  unsigned char h[44];
  if (!f.read(reinterpret_cast<char*>(h), 44) || std::memcmp(h, "RIFF", 4) != 0 ||
      std::memcmp(h + 8, "WAVEfmt ", 8) != 0 || std::memcmp(h + 36, "data", 4) != 0 || h[20] != 1 ||
      h[22] != 1 || h[34] != 16) {
    throw std::runtime_error(path + ": not a 16-bit PCM mono WAV file");
  }
  *sample_rate_hz = static_cast<int>(GetU32(h + 24));
  const std::uint32_t n = GetU32(h + 40) / 2;
  std::vector<float> out(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    unsigned char b[2];
    if (!f.read(reinterpret_cast<char*>(b), 2)) throw std::runtime_error(path + ": truncated");
    out[i] = static_cast<float>(static_cast<std::int16_t>(b[0] | (b[1] << 8))) / 32767.0f;
  }
  return out;
}

}  // namespace microdex::cues
