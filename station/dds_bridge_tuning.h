#pragma once
// How the two ends of the DDS device bridge (the station's DdsDevice and a driver,
// device_driver.h) set up their participants for a short round trip. Both parts are on by
// default; microdex-bench device --compare measures a run with and one without them
// (station/README.md, "DDS device bridge").
//
//   shm: the participant comes from kDeviceBridgeParticipantProfile, whose data locators
//        include shared memory (the default participant of loopback.xml announces only UDPv4
//        on 127.0.0.1); a profile file without it falls back to the default participant.
//   rt:  the threads Fast DDS starts for the participant (its receive threads, which run the
//        listeners, and its event thread) run SCHED_FIFO just below the end's servo thread.
//        Fast DDS 2.9 has no thread settings in XML: they are the threads that appeared while
//        the participant and its endpoints were created. Without the privilege they stay at
//        normal priority.
//   cpu: the end's process asks the kernel for a CPU wake-up latency of 0 µs while it runs
//        (a PM QoS request held open on /dev/cpu_dma_latency, as real-time audio and
//        cyclictest do): idle cores poll instead of halting, so the threads the bridge wakes
//        (the listener, the servo thread) run without an idle exit first. On this project's
//        VM (cpuidle haltpoll) an idle machine had the round trip's median at 192 µs without
//        it and 104-125 µs with it; it costs idle cores their sleep. Without the privilege
//        (root) nothing is requested.

#include <string>

#include "common/net/dds_context.h"

namespace microdex::station {

struct DdsBridgeTuning {
  bool shared_memory = true;
  bool realtime_threads = true;
  bool cpu_latency = true;

  // "all" (the default), "none", or a comma list of "shm", "rt" and "cpu". Empty when valid;
  // otherwise a reason that names the text.
  static std::string Parse(const std::string& text, DdsBridgeTuning* out);
  std::string Name() const;  // the parts on, in the order shm, rt, cpu, comma-separated; "none"
  // The options of the bridge's participant: `dds` with the participant profile chosen.
  net::DdsOptions Apply(net::DdsOptions dds) const;
};

// A PM QoS CPU latency request of 0 µs, held while the object lives (/dev/cpu_dma_latency;
// the kernel drops it when the file is closed, also when the process dies).
class CpuLatencyRequest {
 public:
  CpuLatencyRequest();  // never throws: held() says whether the kernel took it
  ~CpuLatencyRequest();
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;
  bool held() const { return fd_ >= 0; }
  const std::string& why_not() const { return why_not_; }

 private:
  int fd_ = -1;
  std::string why_not_;
};

}  // namespace microdex::station
