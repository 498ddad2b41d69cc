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
// locks or blocks there (WaitForSample is the tick's pacing wait).

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "common/net/dds_context.h"
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
  // Creates the bridge's participant, reader, writer and publisher thread (throws
  // std::runtime_error naming the profile or entity that failed).
  DdsDevice(const net::DdsOptions& dds, const std::string& station_id,
            const std::string& session_id, const DeviceMappingDef& mapping = {},
            const DeviceGuardDef& guard = {});
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
  std::uint64_t forces_dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  // The plain copy of a sample that crosses from the listener to the haptic thread.
  struct BridgeSample {
    double p[3];
    double q[4];
    double gripper;
    std::uint32_t buttons;
    std::uint64_t step;
    std::int64_t stamp_ns;
  };
  struct ForceOut {
    std::uint64_t step;
    std::uint64_t sample_step;
    std::int64_t sample_stamp_ns;
    double f_D[3];
    double tau_D[3];
    std::uint8_t fault;
  };
  class Listener;
  void OnSample(const BridgeSample& s);  // DDS listener thread
  void RunPublisher();                   // the bridge's publisher thread

  std::string station_id_;
  std::string session_id_;
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
  rt::MonotonicClock clock_;
  // Haptic thread only.
  DeviceGuard guard_;
  DeviceMapping mapping_;
  RawDeviceSample raw_;
  DeviceFault fault_ = DeviceFault::kNone;
  std::uint64_t step_ = 0;
  std::thread publisher_;
};

}  // namespace microdex::station
