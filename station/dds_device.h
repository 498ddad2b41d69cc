#pragma once
// --device dds: the DDS device bridge. An external driver process (microdex-device-example,
// or the driver of a real haptic device) publishes its samples on the DeviceSample topic
// (type DeviceInput, key: the station it drives) at 1 kHz and reads the station's force on the
// DeviceForce topic (idl/device_force.idl); both best-effort, keep-last 1 (profiles
// microdex_device_bridge_* in deploy/dds). station/README.md ("DDS device bridge") is the
// protocol for driver writers.
//
// Threads: the DDS listener thread takes each sample, copies it into a latest-value triple
// buffer and wakes the haptic thread (rt::FutexEvent); the haptic thread reads the latest
// sample in Read() (the device paces the loop: a tick follows each sample), passes it through
// the device guard (faults: timeout, non-finite, jump) and the workspace mapping (scale,
// clutch), and in WriteForce() hands the force, in the device frame, through an SPSC ring to
// the bridge's publisher thread, which writes DeviceForce. The haptic thread never allocates,
// locks or blocks there (WaitForSample is the tick's pacing wait). The bridge's participant is
// its own, set up as DdsBridgeTuning says (dds_bridge_tuning.h: shared memory, its Fast DDS
// threads SCHED_FIFO kDdsThreadPriority).

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/net/dds_context.h"
#include "station/dds_bridge_tuning.h"
#include "station/device.h"
#include "station/device_guard.h"
#include "station/device_mapping.h"
#include "station/rt/clock.h"
#include "station/rt/futex_event.h"
#include "station/rt/spsc_ring.h"
#include "station/rt/triple_buffer.h"

namespace microdex::station {

// The instance key of a bimanual station's second device on the bridge's topics: STATION/2
// (the first device's key is the station id). A driver of two devices publishes each under
// its key and reads each one's force under the same key.
std::string SecondDeviceKey(const std::string& station_id);

class DdsDevice final : public Device {
 public:
  // Creates the bridge's participant (tuned as `tuning` says), reader, writer and publisher
  // thread (throws std::runtime_error naming the profile or entity that failed).
  DdsDevice(const net::DdsOptions& dds, const std::string& station_id,
            const std::string& session_id, const DeviceMappingDef& mapping = {},
            const DeviceGuardDef& guard = {}, const DdsBridgeTuning& tuning = {});
  ~DdsDevice() override;
  DdsDevice(const DdsDevice&) = delete;
  DdsDevice& operator=(const DdsDevice&) = delete;

  DeviceSample Read(std::uint64_t step) override;
  void WriteForce(const Eigen::Vector3d& f_T_W) override;
  void WriteWrench(const Eigen::Vector3d& f_T_W, const Eigen::Vector3d& tau_T_W) override;
  bool paces_loop() const override { return true; }
  bool WaitForSample(std::int64_t until_ns) override;

  // Any thread: samples received (valid or not) and forces the ring could not take.
  std::uint64_t samples_received() const { return received_.load(std::memory_order_relaxed); }
  // Any thread: samples addressed to this device that fail net::FromMsg's checks (a number
  // not finite, a quaternion not of unit length, a gripper outside 0..1, a position beyond
  // 10 m, an id not printable). Those with a number that is not finite still go to the guard
  // (its fault holds the last valid sample); the others are dropped here.
  std::uint64_t samples_invalid() const { return invalid_.load(std::memory_order_relaxed); }
  std::uint64_t forces_dropped() const { return dropped_.load(std::memory_order_relaxed); }
  // The participant's Fast DDS threads made SCHED_FIFO kDdsThreadPriority (tuning rt), and
  // the participant profile it came from.
  int dds_threads_realtime() const { return dds_threads_realtime_; }
  // Whether the PM QoS CPU latency request is held (DdsBridgeTuning::cpu_latency).
  bool cpu_latency_held() const { return cpu_latency_ && cpu_latency_->held(); }
  const std::string& participant_profile() const { return dds_->participant_profile(); }
  // Just below the haptic thread (80): a sample reaches the tick as soon as it arrives.
  static constexpr int kDdsThreadPriority = 79;

  // The way of one force through the station, CLOCK_REALTIME ns: the driver's sample stamp,
  // the listener's receipt of that sample, the haptic thread's wake, the force computed, the
  // publisher thread's wake, the write's start (the force's stamp_ns) and its return. Recorded
  // (by the publisher thread, into storage reserved at construction) only when the environment
  // names a directory in MICRODEX_DEVICE_HOPS; written there as KEY.hops.csv when the bridge
  // closes (microdex-bench device reads it for its hop breakdown).
  struct Hops {
    std::uint64_t sample_step;
    std::int64_t sample_stamp_ns, received_ns, woken_ns, ready_ns, publisher_woken_ns, write_ns,
        written_ns;
  };
  static constexpr const char* kHopsEnv = "MICRODEX_DEVICE_HOPS";
  static constexpr std::size_t kMaxHops = 600'000;  // 10 min at 1 kHz

 private:
  // The plain copy of a sample that crosses from the listener to the haptic thread.
  struct BridgeSample {
    double p[3];
    double q[4];
    double gripper;
    std::uint32_t buttons;
    std::uint64_t step;
    std::int64_t stamp_ns;
    std::int64_t received_ns;  // CLOCK_REALTIME, when the listener took it
  };
  struct ForceOut {
    std::uint64_t step;
    std::uint64_t sample_step;
    std::int64_t sample_stamp_ns;
    double f_D[3];
    double tau_D[3];
    std::uint8_t fault;
    std::int64_t received_ns, woken_ns, ready_ns;  // CLOCK_REALTIME (Hops)
  };
  class Listener;
  void OnSample(const BridgeSample& s);  // DDS listener thread
  void RunPublisher();                   // the bridge's publisher thread
  void WriteHops() const;                // after the publisher thread ended

  std::string station_id_;
  std::string session_id_;
  int dds_threads_realtime_ = 0;
  std::unique_ptr<CpuLatencyRequest> cpu_latency_;  // DdsBridgeTuning::cpu_latency
  std::unique_ptr<net::DdsContext> dds_;
  std::unique_ptr<Listener> listener_;
  void* reader_ = nullptr;                 // dds::DataReader*
  void* writer_ = nullptr;                 // dds::DataWriter*
  rt::TripleBuffer<BridgeSample> latest_;  // producer: DDS listener; consumer: haptic thread
  rt::FutexEvent sample_event_;            // listener → haptic thread
  std::uint32_t sample_seen_ = 0;          // haptic thread
  rt::SpscRing<ForceOut> forces_{256};     // producer: haptic thread; consumer: publisher
  rt::FutexEvent force_event_;             // haptic thread → publisher thread
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> invalid_{0};
  rt::MonotonicClock clock_;
  // Haptic thread only.
  DeviceGuard guard_;
  DeviceMapping mapping_;
  RawDeviceSample raw_;
  DeviceFault fault_ = DeviceFault::kNone;
  std::uint64_t step_ = 0;
  std::int64_t woken_ns_ = 0;     // the last return of WaitForSample
  std::int64_t received_ns_ = 0;  // the listener's receipt of the sample read last
  // Publisher thread only (then the destructor): the recorded hops, if asked for.
  std::string hops_file_;
  std::vector<Hops> hops_;
  std::thread publisher_;
};

}  // namespace microdex::station
