// The audio block layout (view_audio.h; common/view/src/audio_block.ts reads it): a block
// encoded and decoded again is the same block, byte offsets as documented, and malformed
// messages are refused with their reason.
#include "common/view/view_audio.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace microdex::view {
namespace {

AudioBlock MakeBlock() {
  AudioBlock b;
  b.flags = kAudioStart;
  b.sample_rate_hz = 44100;
  b.samples = 441;
  b.seq = (std::uint64_t{1} << 40) + 7;  // beyond 32 bits
  b.first_step = 123450;
  b.first_stamp_ms = 1'764'000'000'123.456;
  b.cause_step = 123457;
  b.cause_stamp_ms = 1'764'000'000'130.456;
  b.cause = kCauseProximity | kCauseClick;
  b.active_cues = 1u << 10;
  b.tone_hz = 1650.5f;
  b.clearance_m = 3.25e-4f;
  b.geiger_rate_hz = 0;
  b.cause_offset = 308;
  b.sent_ms = 1'764'000'000'141.5;
  for (std::uint32_t i = 0; i < b.samples; ++i) {
    b.pcm[i] = static_cast<float>(0.5 * std::sin(0.1 * i));
  }
  return b;
}

template <class T>
T At(const std::string& s, std::size_t at) {
  T v{};
  std::memcpy(&v, s.data() + at, sizeof(T));
  return v;
}

TEST(ViewAudio, RoundTrip) {
  const AudioBlock b = MakeBlock();
  const std::string bytes = EncodeAudioBlock(b);
  ASSERT_EQ(bytes.size(), kAudioHeaderBytes + 4 * 441);
  // The documented offsets.
  EXPECT_EQ(std::memcmp(bytes.data(), "MDXA", 4), 0);
  EXPECT_EQ(At<std::uint16_t>(bytes, 4), kAudioVersion);
  EXPECT_EQ(At<std::uint32_t>(bytes, 8), 44100u);
  EXPECT_EQ(At<std::uint32_t>(bytes, 12), 441u);
  EXPECT_EQ(At<std::uint64_t>(bytes, 16), b.seq);
  EXPECT_EQ(At<std::uint64_t>(bytes, 24), 123450u);
  EXPECT_EQ(At<double>(bytes, 32), b.first_stamp_ms);
  EXPECT_EQ(At<std::uint64_t>(bytes, 40), 123457u);
  EXPECT_EQ(At<double>(bytes, 48), b.cause_stamp_ms);
  EXPECT_EQ(At<std::uint32_t>(bytes, 56), kCauseProximity | kCauseClick);
  EXPECT_EQ(At<float>(bytes, 64), 1650.5f);
  EXPECT_EQ(At<std::uint32_t>(bytes, 76), 308u);
  EXPECT_EQ(At<double>(bytes, 80), b.sent_ms);
  EXPECT_EQ(At<float>(bytes, kAudioHeaderBytes + 4 * 440), b.pcm[440]);

  const AudioBlock d = DecodeAudioBlock(bytes.data(), bytes.size());
  EXPECT_EQ(d.flags, b.flags);
  EXPECT_EQ(d.sample_rate_hz, b.sample_rate_hz);
  EXPECT_EQ(d.samples, b.samples);
  EXPECT_EQ(d.seq, b.seq);
  EXPECT_EQ(d.first_step, b.first_step);
  EXPECT_EQ(d.first_stamp_ms, b.first_stamp_ms);
  EXPECT_EQ(d.cause_step, b.cause_step);
  EXPECT_EQ(d.cause_stamp_ms, b.cause_stamp_ms);
  EXPECT_EQ(d.cause, b.cause);
  EXPECT_EQ(d.active_cues, b.active_cues);
  EXPECT_EQ(d.tone_hz, b.tone_hz);
  EXPECT_EQ(d.clearance_m, b.clearance_m);
  EXPECT_EQ(d.geiger_rate_hz, b.geiger_rate_hz);
  EXPECT_EQ(d.cause_offset, b.cause_offset);
  EXPECT_EQ(d.sent_ms, b.sent_ms);
  for (std::uint32_t i = 0; i < b.samples; ++i) ASSERT_EQ(d.pcm[i], b.pcm[i]) << i;
}

TEST(ViewAudio, NoWallAndCauseBeforeSurvive) {
  AudioBlock b = MakeBlock();
  b.clearance_m = std::numeric_limits<float>::infinity();
  b.cause_offset = kCauseBefore;
  b.samples = 1;
  const std::string bytes = EncodeAudioBlock(b);
  const AudioBlock d = DecodeAudioBlock(bytes.data(), bytes.size());
  EXPECT_TRUE(std::isinf(d.clearance_m));
  EXPECT_EQ(d.cause_offset, kCauseBefore);
  EXPECT_EQ(d.samples, 1u);
}

void ExpectRefused(const std::string& bytes, const std::string& reason) {
  try {
    DecodeAudioBlock(bytes.data(), bytes.size());
    ADD_FAILURE() << "accepted; expected: " << reason;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("audio block: ", 0), 0u) << e.what();
  }
}

TEST(ViewAudio, MalformedBlocksAreRefused) {
  const std::string good = EncodeAudioBlock(MakeBlock());
  ExpectRefused(good.substr(0, 87), "shorter than its header");
  ExpectRefused(good.substr(0, good.size() - 4), "441 samples in");
  ExpectRefused(good + "abcd", "441 samples in");
  std::string s = good;
  s[0] = 'X';
  ExpectRefused(s, "magic");
  s = good;
  s[4] = 9;
  ExpectRefused(s, "version 9");
  s = good;
  const std::uint32_t rate = 1000;
  std::memcpy(s.data() + 8, &rate, 4);
  ExpectRefused(s, "sample rate 1000 Hz");
  s = good;
  const std::uint32_t offset = 441;
  std::memcpy(s.data() + 76, &offset, 4);
  ExpectRefused(s, "cause at sample 441 of 441");
  s = good;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(s.data() + kAudioHeaderBytes + 4 * 17, &nan, 4);
  ExpectRefused(s, "sample 17");
  s = good;
  const float loud = 1.5f;
  std::memcpy(s.data() + kAudioHeaderBytes, &loud, 4);
  ExpectRefused(s, "sample 0");
  s = good;
  const std::uint32_t many = kMaxAudioBlockSamples + 1;
  std::memcpy(s.data() + 12, &many, 4);
  ExpectRefused(s, "1025 samples");
}

}  // namespace
}  // namespace microdex::view
