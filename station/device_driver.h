#pragma once
// A DDS device driver (the other end of the station's DDS device bridge, station/dds_device.h):
// publishes hand samples on the DeviceSample topic at rate_hz, from a CSV file (the columns of
// station/playback_device.h, in the device frame) or a built-in script (a slow circle), and
// reads the station's force on the DeviceForce topic, timing each round trip (the sample's
// stamp comes back in the force that answers it). It can misbehave on purpose (stop sending,
// send NaN, jump) to exercise the station's fault handling. microdex-device-example and
// microdex-bench device run it.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "common/net/dds_context.h"
#include "station/dds_bridge_tuning.h"

namespace microdex::station {

enum class DriverFault { kNone, kStop, kNaN, kJump };

struct DeviceDriverDef {
  std::string station_id;
  double rate_hz = 1000;
  double duration_s = 5;  // of sending, after the station is found
  std::string csv;        // hand samples, one per period (repeats the last row); "" the script
  double circle_radius_m = 0.01;
  double circle_hz = 0.25;
  DriverFault fault = DriverFault::kNone;
  double fault_at_s = 1;
  double fault_for_s = 0.05;
  double discovery_timeout_s = 10;  // waiting for the station's bridge
  // The driver's participant (dds_bridge_tuning.h); its rt threads run SCHED_FIFO
  // kDriverDdsThreadPriority, just below the sending thread's kDriverPriority.
  DdsBridgeTuning tuning;
  // Empty when valid; otherwise "field: reason".
  std::string Validate() const;
};

// One answered sample at the driver, CLOCK_REALTIME ns: its stamp (just before the write), the
// write's return, the answering force's stamp (the station's write start) and its receipt.
struct DriverHop {
  std::uint64_t sample_step = 0;
  std::int64_t sample_stamp_ns = 0, write_returned_ns = 0, force_stamp_ns = 0, received_ns = 0;
};

struct DriverStats {
  std::uint64_t sent = 0;
  std::uint64_t forces = 0;           // DeviceForce samples received
  std::uint64_t answered = 0;         // samples echoed by at least one force
  std::uint64_t lost = 0;             // samples sent and never answered
  std::uint64_t fault_forces = 0;     // forces flagged with a device fault
  std::vector<double> round_trip_us;  // send → the force that echoes it
  std::vector<DriverHop> hops;        // one per answered sample, in order of receipt
  double force_max_N = 0;
  double torque_max_Nm = 0;      // largest |tau_D| received
  bool matched = false;          // the station's bridge was found
  bool realtime = false;         // the sending thread ran SCHED_FIFO
  int dds_threads_realtime = 0;  // the participant's threads made SCHED_FIFO (tuning rt)
};

inline constexpr int kDriverPriority = 70;
inline constexpr int kDriverDdsThreadPriority = 69;

// Runs the driver until duration_s has passed or `stop`; throws std::runtime_error (DDS
// profile, CSV file) with a one-line reason.
DriverStats RunDeviceDriver(const net::DdsOptions& dds, const DeviceDriverDef& def,
                            const std::atomic<bool>& stop);

// The q-quantile of v (sorted copy), NaN when empty.
double Quantile(std::vector<double> v, double q);

}  // namespace microdex::station
