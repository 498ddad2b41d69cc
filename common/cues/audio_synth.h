#pragma once
// The audio cues as PCM (thesis §2.1, §4.1: "an audio warning cue ... with volume or pitch
// rising as distance to the tube decreases"; "the click of a Geiger counter"). Synthesis is a
// pure function of the step's cue signals (AudioCueFrame, from state::CueState) and of the
// synthesiser's own oscillator state; it runs outside the haptic thread (the station's
// --audio-out, the page's Web Audio). README.md in this folder gives the formulas.
//
// No allocation: the caller hands the output block.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/cues/cue_kind.h"

namespace microdex::cues {

struct AudioSynthDef {
  double sample_rate_hz = 44100;
  double tone_low_hz = 220;    // audio_proximity at the edge of its range
  double tone_high_hz = 1760;  // ... at contact (three octaves higher)
  double tone_min_amplitude = 0.05;
  double tone_max_amplitude = 0.5;
  double geiger_min_rate_hz = 2;    // audio_geiger at the edge of its range
  double geiger_max_rate_hz = 200;  // ... at contact
  double click_hz = 2500;           // the click's ring (contact click and Geiger click)
  double click_s = 0.004;           // the contact click's decay time constant
  double geiger_click_s = 0.001;    // the Geiger click's (short: clicks stay apart at 200 Hz)
  double error_hz = 330;            // the error tone, beeping at error_beep_hz
  double error_beep_hz = 4;
  double warning_hz = 1000;  // the predictive warning, beeping at 8 Hz
  // Throws std::invalid_argument("field: reason").
  void Validate() const;
};

// One step's audio cue inputs (what CueState holds after the step).
struct AudioCueFrame {
  std::uint32_t active = 0;  // bit CueBit(kind) per cue on
  std::array<double, kCueKindCount> param{};
  double clearance_m = 0;  // +inf: no wall
  bool click = false;      // a contact began this step
  bool error = false;      // at fault this step
  bool warning = false;    // the predictive cue's warning
};

// The oscillators' phases and the Geiger counter's generator (deterministic, seeded).
struct AudioSynthState {
  double tone_phase = 0;
  double error_phase = 0;
  double beep_phase = 0;
  double warning_phase = 0;
  double click_age_s = 1e9;  // time since the last click started
  double click_gain = 0;
  double click_tau_s = 0.004;
  double geiger_wait_s = 0;  // until the next Geiger click
  std::uint64_t rng = 0x853c49e6748fea9bULL;
};

// audio_proximity: 0 at the edge of the range (or beyond), 1 at contact (or below).
double CalcProximity(double clearance_m, double range_m);
// The tone's pitch and amplitude, and the Geiger counter's mean click rate, at a proximity.
double CalcToneHz(const AudioSynthDef& def, double proximity);
double CalcToneAmplitude(const AudioSynthDef& def, double proximity);
double CalcGeigerRateHz(const AudioSynthDef& def, double proximity);

// Renders out.size() mono samples in [−1, 1] with the frame held over them.
void SynthesizeAudio(const AudioSynthDef& def, const AudioCueFrame& frame, AudioSynthState& state,
                     std::span<float> out);

// A 16-bit PCM mono WAV file (RIFF, 44-byte header). Throws std::runtime_error naming the path
// when it cannot be written.
void WriteWav(const std::string& path, std::span<const float> samples, int sample_rate_hz);
// Reads back a file WriteWav wrote (tests); throws std::runtime_error on anything else.
std::vector<float> ReadWav(const std::string& path, int* sample_rate_hz);

}  // namespace microdex::cues
