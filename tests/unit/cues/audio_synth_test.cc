// Audio cues: the proximity tone's pitch (found with a DFT) and loudness rise as the
// clearance falls; the Geiger counter's click rate rises with proximity; the contact click and
// the error tone sound only when on; the WAV file reads back.
#include "common/cues/audio_synth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <vector>

namespace microdex::cues {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRange_m = 1e-3;

AudioCueFrame Frame(CueKind kind, double param, double clearance_m) {
  AudioCueFrame f;
  f.active = CueBit(kind);
  f.param[static_cast<std::size_t>(kind)] = param;
  f.clearance_m = clearance_m;
  return f;
}

std::vector<float> Render(const AudioCueFrame& f, double seconds,
                          AudioSynthState* state = nullptr) {
  const AudioSynthDef def;
  AudioSynthState local;
  std::vector<float> out(static_cast<std::size_t>(seconds * def.sample_rate_hz));
  SynthesizeAudio(def, f, state != nullptr ? *state : local, out);
  return out;
}

// The frequency of the largest DFT bin (Hann window), 20 Hz .. 5 kHz, refined by a parabola
// through the peak's neighbours.
double PeakHz(const std::vector<float>& x, double rate_hz) {
  const std::size_t n = x.size();
  const std::size_t k_lo = static_cast<std::size_t>(20.0 * n / rate_hz);
  const std::size_t k_hi = static_cast<std::size_t>(5000.0 * n / rate_hz);
  std::vector<double> mag(k_hi + 2, 0.0);
  for (std::size_t k = k_lo; k <= k_hi + 1; ++k) {
    std::complex<double> s = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double w = 0.5 - 0.5 * std::cos(2 * kPi * static_cast<double>(i) / (n - 1));
      s += w * x[i] * std::polar(1.0, -2 * kPi * static_cast<double>(k * i) / n);
    }
    mag[k] = std::abs(s);
  }
  std::size_t best = k_lo + 1;
  for (std::size_t k = k_lo + 1; k <= k_hi; ++k) {
    if (mag[k] > mag[best]) best = k;
  }
  const double a = mag[best - 1], b = mag[best], c = mag[best + 1];
  const double delta = 0.5 * (a - c) / (a - 2 * b + c);
  return (static_cast<double>(best) + delta) * rate_hz / static_cast<double>(n);
}

double Rms(const std::vector<float>& x) {
  double s = 0;
  for (float v : x) s += static_cast<double>(v) * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

// Clicks: bursts above a threshold on the rectified signal, apart by at least 0.8 ms of quiet.
int CountClicks(const std::vector<float>& x, double rate_hz) {
  int clicks = 0;
  std::ptrdiff_t last = -1000000;
  const auto gap = static_cast<std::ptrdiff_t>(0.0008 * rate_hz);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto ii = static_cast<std::ptrdiff_t>(i);
    if (std::abs(x[i]) > 0.2 && ii - last > gap) ++clicks;
    if (std::abs(x[i]) > 0.2) last = ii;
  }
  return clicks;
}

TEST(AudioSynth, ProximityPitchAndLoudnessRiseAsTheClearanceFalls) {
  const AudioSynthDef def;
  double prev_hz = 0, prev_rms = 0;
  // From the edge of the range to contact and beyond.
  for (double c : {0.95e-3, 0.8e-3, 0.6e-3, 0.4e-3, 0.2e-3, 0.05e-3, 0.0, -0.1e-3}) {
    SCOPED_TRACE(c);
    const std::vector<float> x =
        Render(Frame(CueKind::kAudioProximity, kRange_m, c), 8192 / def.sample_rate_hz);
    const double hz = PeakHz(x, def.sample_rate_hz);
    const double expected = CalcToneHz(def, CalcProximity(c, kRange_m));
    EXPECT_NEAR(hz, expected, 0.01 * expected) << "the tone is at the formula's pitch";
    const double rms = Rms(x);
    if (c > 0) {
      EXPECT_GT(hz, prev_hz * 1.01) << "pitch strictly rises as the clearance falls";
      EXPECT_GT(rms, prev_rms) << "loudness strictly rises as the clearance falls";
    } else {
      EXPECT_GE(hz, prev_hz * 0.999) << "at and past contact: the top of the scale";
    }
    prev_hz = hz;
    prev_rms = rms;
  }
  // Beyond the range, or with the cue off: silence.
  EXPECT_EQ(Rms(Render(Frame(CueKind::kAudioProximity, kRange_m, 2e-3), 0.05)), 0.0);
  AudioCueFrame off = Frame(CueKind::kAudioProximity, kRange_m, 0.1e-3);
  off.active = 0;
  EXPECT_EQ(Rms(Render(off, 0.05)), 0.0);
}

TEST(AudioSynth, GeigerClickRateRisesWithProximity) {
  const AudioSynthDef def;
  int prev = -1;
  for (double c : {0.9e-3, 0.7e-3, 0.5e-3, 0.3e-3, 0.1e-3}) {
    SCOPED_TRACE(c);
    const std::vector<float> x = Render(Frame(CueKind::kAudioGeiger, kRange_m, c), 4.0);
    const int clicks = CountClicks(x, def.sample_rate_hz);
    const double expected = 4.0 * CalcGeigerRateHz(def, CalcProximity(c, kRange_m));
    EXPECT_NEAR(clicks, expected, 0.15 * expected + 3) << "the mean rate of the formula";
    EXPECT_GT(clicks, prev) << "more clicks, closer to the wall";
    prev = clicks;
  }
  EXPECT_EQ(
      CountClicks(Render(Frame(CueKind::kAudioGeiger, kRange_m, 2e-3), 1.0), def.sample_rate_hz),
      0);
}

TEST(AudioSynth, ClickAndErrorSoundOnlyWhenOn) {
  AudioCueFrame f = Frame(CueKind::kAudioClick, 0.8, 1.0);
  f.click = true;
  AudioSynthState s;
  const std::vector<float> click = Render(f, 0.04, &s);
  EXPECT_EQ(CountClicks(click, 44100), 1);
  f.click = false;
  EXPECT_EQ(Rms(Render(f, 0.05, &s)), 0.0) << "the click dies away";
  f.click = true;
  f.active = 0;
  EXPECT_EQ(Rms(Render(f, 0.02)), 0.0);
  AudioCueFrame e = Frame(CueKind::kAudioError, 0.5, 1.0);
  EXPECT_EQ(Rms(Render(e, 0.1)), 0.0) << "no error, no tone";
  e.error = true;
  EXPECT_GT(Rms(Render(e, 0.25)), 0.1);
}

TEST(AudioSynth, WavFileReadsBack) {
  const std::vector<float> x = Render(Frame(CueKind::kAudioProximity, kRange_m, 0.3e-3), 0.1);
  const std::string path =
      (std::filesystem::temp_directory_path() / "microdex_audio_synth_test.wav").string();
  WriteWav(path, x, 44100);
  EXPECT_EQ(std::filesystem::file_size(path), 44 + 2 * x.size()) << "44-byte header + 16-bit";
  int rate = 0;
  const std::vector<float> y = ReadWav(path, &rate);
  EXPECT_EQ(rate, 44100);
  ASSERT_EQ(y.size(), x.size());
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(y[i], x[i], 1.0 / 32767 + 1e-7);
  std::remove(path.c_str());
  EXPECT_THROW(WriteWav("/nonexistent-dir/x.wav", x, 44100), std::runtime_error);
}

}  // namespace
}  // namespace microdex::cues
