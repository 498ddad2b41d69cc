// The page's audio blocks (station/audio_out.h AudioBlockStream): the same samples as
// --audio-out's synthesis, cut into 441-sample blocks stamped with the step and tick stamp of
// their first sample and of the most recent cause (with its sample's index); nothing while no
// page asks or no audio cue is on; a short last block when that ends; no allocation per step.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "station/audio_out.h"
#include "tests/support/alloc_counter.h"

namespace microdex::station {
namespace {

using cues::CueBit;
using cues::CueKind;

constexpr std::int64_t kT0 = 1'764'000'000'000'000'000;  // CLOCK_REALTIME ns of step 0

TickSnapshot Step(std::uint64_t step, std::uint32_t cues, double clearance_m, bool click = false) {
  TickSnapshot s;
  s.step = step;
  s.stamp_ns = kT0 + static_cast<std::int64_t>(step) * 1'000'000 + 1234;
  s.active_cues = cues;
  s.cue.param = cues::kCueParamDefaults;
  s.cue.param[static_cast<std::size_t>(CueKind::kAudioProximity)] = 0.01;
  s.cue.clearance_m = clearance_m;
  s.cue.click = click ? 1 : 0;
  return s;
}

struct Collected {
  std::vector<view::AudioBlock> blocks;
  bool accept = true;
  AudioBlockStream::Sink Sink() {
    return [this](const view::AudioBlock& b) {
      if (!accept) return false;
      blocks.push_back(b);
      return true;
    };
  }
};

double StampMs(std::uint64_t step) {
  return static_cast<double>(kT0 + static_cast<std::int64_t>(step) * 1'000'000 + 1234) * 1e-6;
}

TEST(AudioBlockStream, BlocksCarryAudioOutsSamplesAndStamps) {
  const std::uint32_t cues = CueBit(CueKind::kAudioProximity);
  Collected c;
  AudioBlockStream stream(1000, c.Sink());
  AudioOut file(1000);
  std::vector<std::size_t> first_sample;  // of each step in the whole stream
  const int steps = 1000;
  for (int k = 0; k < steps; ++k) {
    const TickSnapshot s = Step(k, cues, 0.4e-3 + 0.2e-3 * std::sin(0.01 * k));
    first_sample.push_back(file.samples().size());
    file.Add(s);
    stream.Add(s, true);
  }
  // 44 100 samples in 1000 steps at 44.1 kHz: exactly 100 blocks of 441.
  ASSERT_EQ(file.samples().size(), 44100u);
  ASSERT_EQ(c.blocks.size(), 100u);
  std::size_t at = 0;
  for (std::size_t i = 0; i < c.blocks.size(); ++i) {
    const view::AudioBlock& b = c.blocks[i];
    EXPECT_EQ(b.seq, i);
    EXPECT_EQ(b.samples, 441u);
    EXPECT_EQ(b.sample_rate_hz, 44100u);
    EXPECT_EQ(b.flags, i == 0 ? view::kAudioStart : 0);
    EXPECT_EQ(b.active_cues, cues);
    // The step whose samples hold the block's first sample.
    std::uint64_t step = 0;
    while (step + 1 < first_sample.size() && first_sample[step + 1] <= at) ++step;
    EXPECT_EQ(b.first_step, step) << i;
    EXPECT_DOUBLE_EQ(b.first_stamp_ms, StampMs(step));
    // The clearance changes every step: the cause is the block's last step, at its first sample.
    std::uint64_t last = step;
    while (last + 1 < first_sample.size() && first_sample[last + 1] < at + 441) ++last;
    EXPECT_EQ(b.cause_step, last) << i;
    EXPECT_DOUBLE_EQ(b.cause_stamp_ms, StampMs(last));
    EXPECT_EQ(b.cause & view::kCauseProximity, view::kCauseProximity);
    ASSERT_NE(b.cause_offset, view::kCauseBefore);
    EXPECT_EQ(b.cause_offset, first_sample[last] - at) << i;
    // The pitch of that last step.
    const double x = cues::CalcProximity(0.4e-3 + 0.2e-3 * std::sin(0.01 * last), 0.01);
    EXPECT_NEAR(b.tone_hz, cues::CalcToneHz({}, x), 1e-3 * b.tone_hz);
    for (std::uint32_t j = 0; j < b.samples; ++j) {
      ASSERT_EQ(b.pcm[j], file.samples()[at + j]) << "block " << i << " sample " << j;
    }
    at += b.samples;
  }
}

TEST(AudioBlockStream, AClickIsTheCauseAtItsStep) {
  const std::uint32_t cues = CueBit(CueKind::kAudioClick);
  Collected c;
  AudioBlockStream stream(1000, c.Sink());
  for (int k = 0; k < 40; ++k) stream.Add(Step(k, cues, 1e-3, k == 23), true);
  ASSERT_EQ(c.blocks.size(), 4u);
  // Block 0 starts the stream (cause: the cue on at step 0); block 2 holds step 23 (samples
  // 1014..1058, 132 into the block that starts at 882).
  EXPECT_EQ(c.blocks[0].cause, view::kCauseCueOn);
  EXPECT_EQ(c.blocks[0].cause_offset, 0u);
  EXPECT_EQ(c.blocks[1].cause_step, 0u);
  EXPECT_EQ(c.blocks[1].cause_offset, view::kCauseBefore);
  EXPECT_EQ(c.blocks[2].cause, view::kCauseClick);
  EXPECT_EQ(c.blocks[2].cause_step, 23u);
  EXPECT_DOUBLE_EQ(c.blocks[2].cause_stamp_ms, StampMs(23));
  EXPECT_EQ(c.blocks[2].first_step, 20u);
  EXPECT_EQ(c.blocks[2].cause_offset, 1014u - 882u);
  // The click sounds from there, not before.
  EXPECT_EQ(c.blocks[2].pcm[c.blocks[2].cause_offset - 1], 0.0f);
  double energy = 0;
  for (std::uint32_t j = c.blocks[2].cause_offset; j < 441; ++j) {
    energy += c.blocks[2].pcm[j] * c.blocks[2].pcm[j];
  }
  EXPECT_GT(energy, 1.0);
  EXPECT_EQ(c.blocks[3].cause_step, 23u);
  EXPECT_EQ(c.blocks[3].cause_offset, view::kCauseBefore);
}

TEST(AudioBlockStream, NothingUnlessAskedAndAnAudioCueIsOn) {
  Collected c;
  AudioBlockStream stream(1000, c.Sink());
  const std::uint32_t tone = CueBit(CueKind::kAudioProximity);
  for (int k = 0; k < 100; ++k) stream.Add(Step(k, tone, 1e-3), false);  // no page asked
  for (int k = 100; k < 200; ++k) {
    stream.Add(Step(k, CueBit(CueKind::kVisualPath) | CueBit(CueKind::kConvergentField), 1e-3),
               true);  // no audio cue
  }
  EXPECT_TRUE(c.blocks.empty());
  // Asked and on from step 200; the page leaves at step 215: a short last block.
  for (int k = 200; k < 215; ++k) stream.Add(Step(k, tone, 1e-3), true);
  stream.Add(Step(215, tone, 1e-3), false);
  ASSERT_EQ(c.blocks.size(), 2u);
  EXPECT_EQ(c.blocks[0].flags, view::kAudioStart);
  EXPECT_EQ(c.blocks[0].first_step, 200u);
  EXPECT_EQ(c.blocks[1].flags, view::kAudioEnd);
  EXPECT_EQ(c.blocks[1].first_step, 210u);
  EXPECT_EQ(c.blocks[1].samples, 15u * 441u / 10u - 441u);  // 661 samples in all
  // Back at step 300: a new stream, fresh oscillators (its first block as the first ever).
  for (int k = 300; k < 310; ++k) stream.Add(Step(k, tone, 1e-3), true);
  ASSERT_EQ(c.blocks.size(), 3u);
  EXPECT_EQ(c.blocks[2].flags, view::kAudioStart);
  EXPECT_EQ(c.blocks[2].seq, 2u);
  EXPECT_EQ(c.blocks[2].first_step, 300u);
  for (std::uint32_t j = 0; j < 441; ++j) ASSERT_EQ(c.blocks[2].pcm[j], c.blocks[0].pcm[j]) << j;
}

TEST(AudioBlockStream, AFullSinkCountsDroppedBlocks) {
  Collected c;
  c.accept = false;
  AudioBlockStream stream(1000, c.Sink());
  for (int k = 0; k < 50; ++k) stream.Add(Step(k, CueBit(CueKind::kAudioGeiger), 0.5e-3), true);
  EXPECT_EQ(stream.blocks(), 5u);
  EXPECT_EQ(stream.dropped(), 5u);
}

TEST(AudioBlockStream, BadArgumentsAreNamed) {
  Collected c;
  EXPECT_THROW(AudioBlockStream(1000, c.Sink(), 0), std::invalid_argument);
  EXPECT_THROW(AudioBlockStream(1000, c.Sink(), view::kMaxAudioBlockSamples + 1),
               std::invalid_argument);
  EXPECT_THROW(AudioBlockStream(0, c.Sink()), std::invalid_argument);
  EXPECT_THROW(AudioBlockStream(1000, nullptr), std::invalid_argument);
}

TEST(AudioBlockStream, AStepAllocatesNothing) {
  std::array<view::AudioBlock, 4> ring;
  std::size_t n = 0;
  AudioBlockStream stream(1000, [&](const view::AudioBlock& b) {
    ring[n++ % ring.size()] = b;
    return true;
  });
  const std::uint32_t cues = CueBit(CueKind::kAudioProximity) | CueBit(CueKind::kAudioGeiger) |
                             CueBit(CueKind::kAudioClick);
  stream.Add(Step(0, cues, 1e-3), true);
  testing::StartCountingAllocations();
  for (int k = 1; k < 500; ++k) stream.Add(Step(k, cues, 0.3e-3, k % 97 == 0), k % 200 != 0);
  EXPECT_EQ(testing::StopCountingAllocations(), 0u);
  EXPECT_GT(n, 40u);
}

}  // namespace
}  // namespace microdex::station
