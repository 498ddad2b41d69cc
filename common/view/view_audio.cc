#include "common/view/view_audio.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace microdex::view {
namespace {

template <class T>
void Put(std::string& out, std::size_t at, T v) {
  std::memcpy(out.data() + at, &v, sizeof(T));
}

template <class T>
T Get(const std::uint8_t* p, std::size_t at) {
  T v{};
  std::memcpy(&v, p + at, sizeof(T));
  return v;
}

}  // namespace

std::string EncodeAudioBlock(const AudioBlock& b) {
  const std::size_t n = std::min<std::size_t>(b.samples, kMaxAudioBlockSamples);
  std::string out(kAudioHeaderBytes + 4 * n, '\0');
  Put<std::uint32_t>(out, 0, kAudioMagic);
  Put<std::uint16_t>(out, 4, kAudioVersion);
  Put<std::uint16_t>(out, 6, b.flags);
  Put<std::uint32_t>(out, 8, b.sample_rate_hz);
  Put<std::uint32_t>(out, 12, static_cast<std::uint32_t>(n));
  Put<std::uint64_t>(out, 16, b.seq);
  Put<std::uint64_t>(out, 24, b.first_step);
  Put<double>(out, 32, b.first_stamp_ms);
  Put<std::uint64_t>(out, 40, b.cause_step);
  Put<double>(out, 48, b.cause_stamp_ms);
  Put<std::uint32_t>(out, 56, b.cause);
  Put<std::uint32_t>(out, 60, b.active_cues);
  Put<float>(out, 64, b.tone_hz);
  Put<float>(out, 68, b.clearance_m);
  Put<float>(out, 72, b.geiger_rate_hz);
  Put<std::uint32_t>(out, 76, b.cause_offset);
  Put<double>(out, 80, b.sent_ms);
  std::memcpy(out.data() + kAudioHeaderBytes, b.pcm.data(), 4 * n);
  return out;
}

AudioBlock DecodeAudioBlock(const void* data, std::size_t size) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  if (size < kAudioHeaderBytes) {
    throw std::invalid_argument("audio block: " + std::to_string(size) +
                                " bytes, shorter than its header (88)");
  }
  if (Get<std::uint32_t>(p, 0) != kAudioMagic) {
    throw std::invalid_argument("audio block: not an audio block (magic)");
  }
  if (Get<std::uint16_t>(p, 4) != kAudioVersion) {
    throw std::invalid_argument("audio block: version " + std::to_string(Get<std::uint16_t>(p, 4)) +
                                ", expected " + std::to_string(kAudioVersion));
  }
  AudioBlock b;
  b.flags = Get<std::uint16_t>(p, 6);
  b.sample_rate_hz = Get<std::uint32_t>(p, 8);
  b.samples = Get<std::uint32_t>(p, 12);
  if (b.samples > kMaxAudioBlockSamples || size != kAudioHeaderBytes + 4 * std::size_t{b.samples}) {
    throw std::invalid_argument("audio block: " + std::to_string(b.samples) + " samples in " +
                                std::to_string(size) + " bytes");
  }
  if (b.sample_rate_hz < 8000 || b.sample_rate_hz > 192000) {
    throw std::invalid_argument("audio block: sample rate " + std::to_string(b.sample_rate_hz) +
                                " Hz outside 8000..192000");
  }
  b.seq = Get<std::uint64_t>(p, 16);
  b.first_step = Get<std::uint64_t>(p, 24);
  b.first_stamp_ms = Get<double>(p, 32);
  b.cause_step = Get<std::uint64_t>(p, 40);
  b.cause_stamp_ms = Get<double>(p, 48);
  b.cause = Get<std::uint32_t>(p, 56);
  b.active_cues = Get<std::uint32_t>(p, 60);
  b.tone_hz = Get<float>(p, 64);
  b.clearance_m = Get<float>(p, 68);
  b.geiger_rate_hz = Get<float>(p, 72);
  b.cause_offset = Get<std::uint32_t>(p, 76);
  b.sent_ms = Get<double>(p, 80);
  if (b.cause_offset != kCauseBefore && b.cause_offset >= b.samples) {
    throw std::invalid_argument("audio block: cause at sample " + std::to_string(b.cause_offset) +
                                " of " + std::to_string(b.samples));
  }
  std::memcpy(b.pcm.data(), p + kAudioHeaderBytes, 4 * std::size_t{b.samples});
  for (std::uint32_t i = 0; i < b.samples; ++i) {
    if (!(std::abs(b.pcm[i]) <= 1.0f)) {
      throw std::invalid_argument("audio block: sample " + std::to_string(i) +
                                  " is not a number in [-1, 1]");
    }
  }
  return b;
}

}  // namespace microdex::view
