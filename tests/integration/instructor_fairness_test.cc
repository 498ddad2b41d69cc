// A flood on one topic does not hold the others back: three writers send DeviceInput as fast
// as they can (reliable keep-all: each waits for the reader, so a recording instructor's
// input reader is seldom empty) while another station's ToolState arrives at 60 Hz. Every
// tool state is taken, each within a pass or two of the instructor's DDS thread.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/net/convert.h"
#include "common/net/dds_context.h"
#include "common/net/topics.h"
#include "device_inputPubSubTypes.h"
#include "instructor/instructor.h"
#include "tool_statePubSubTypes.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
constexpr int kDomain = 89;
constexpr auto kFlood = 3s;
constexpr int kFlooders = 3;

std::int64_t RealtimeNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

TEST(InstructorFairness, AFloodOfInputsDoesNotHoldBackAnotherStationsStates) {
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain;
  instructor::InstructorOptions options;
  options.dds = dds;
  options.recording_ready = true;  // DeviceInput read with the recording's deep readers
  instructor::Instructor console(options);

  // One participant and writer per flooding station (a DeviceInput writer holds one station),
  // and one for the calm station's tool states.
  std::vector<std::unique_ptr<net::DdsContext>> contexts;
  std::vector<eprosima::fastdds::dds::DataWriter*> writers;
  for (int k = 0; k <= kFlooders; ++k) {
    contexts.push_back(std::make_unique<net::DdsContext>(dds));
    writers.push_back(
        k < kFlooders
            ? contexts.back()->CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceInputTopic)
            : contexts.back()->CreateWriter<msg::ToolStatePubSubType>(net::kToolStateTopic));
    ASSERT_NE(writers.back(), nullptr);
  }
  for (int i = 0; i < 500; ++i) {  // all matched before the flood starts
    int matched = 0;
    for (auto* w : writers) {
      eprosima::fastdds::dds::PublicationMatchedStatus status;
      w->get_publication_matched_status(status);
      matched += status.current_count > 0 ? 1 : 0;
    }
    if (matched == kFlooders + 1) break;
    std::this_thread::sleep_for(10ms);
  }

  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> inputs_written{0};
  std::vector<std::thread> floods;
  for (int k = 0; k < kFlooders; ++k) {
    floods.emplace_back([&, k] {
      net::DeviceInput in;
      in.header.station_id = "flood-" + std::to_string(k);
      in.header.session_id = "flood-run";
      msg::DeviceInput m;
      for (std::uint64_t step = 0; !stop.load(); ++step) {
        in.header.step = step;
        in.header.stamp_ns = RealtimeNs();
        in.p_WT.x() = 1e-6 * static_cast<double>(step % 1000);
        net::ToMsg(in, m);
        if (writers[k]->write(&m)) ++inputs_written;
      }
    });
  }
  // The calm station's 60 Hz tool states, and the longest the console went without a new one.
  net::ToolState ts;
  ts.header.station_id = "calm";
  ts.header.session_id = "calm-run";
  msg::ToolState m;
  std::uint64_t written = 0, last_count = 0;
  auto last_change = std::chrono::steady_clock::now();
  std::chrono::steady_clock::duration longest{0};
  const auto start = std::chrono::steady_clock::now();
  for (auto next = start; next - start < kFlood; next += 16667us) {
    std::this_thread::sleep_until(next);
    ts.header.step = written;
    ts.header.stamp_ns = RealtimeNs();
    net::ToMsg(ts, m);
    if (writers.back()->write(&m)) ++written;
    const std::uint64_t count =
        console.Station("calm").value_or(instructor::StationView{}).tool.count;
    const auto now = std::chrono::steady_clock::now();
    if (count != last_count) {
      last_count = count;
      last_change = now;
    } else {
      longest = std::max(longest, now - last_change);
    }
  }
  stop = true;
  for (std::thread& t : floods) t.join();
  std::this_thread::sleep_for(500ms);  // what is in flight arrives

  const auto calm = console.Station("calm").value_or(instructor::StationView{});
  std::uint64_t inputs_taken = 0;
  for (int k = 0; k < kFlooders; ++k) {
    inputs_taken += console.Station("flood-" + std::to_string(k))
                        .value_or(instructor::StationView{})
                        .inputs_received;
  }
  const double longest_ms = std::chrono::duration<double, std::milli>(longest).count();
  std::printf(
      "%llu inputs written, %llu taken; %llu of %llu tool states taken; longest wait "
      "for a new one %.1f ms\n",
      static_cast<unsigned long long>(inputs_written.load()),
      static_cast<unsigned long long>(inputs_taken),
      static_cast<unsigned long long>(calm.tool.count), static_cast<unsigned long long>(written),
      longest_ms);
  EXPECT_GT(inputs_taken, 20000u) << "the flood is a flood";
  EXPECT_EQ(console.Rejected().total, 0u) << console.Rejected().last_reason;
  EXPECT_EQ(calm.tool.count, written) << "every tool state taken";
  // 60 Hz: a new one every 17 ms; a loaded 2-core host may hold the DDS thread for a while,
  // not for the flood's 3 s.
  EXPECT_LT(longest_ms, 500.0);
}

}  // namespace
}  // namespace microdex
