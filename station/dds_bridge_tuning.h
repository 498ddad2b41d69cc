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

#include <string>

#include "common/net/dds_context.h"

namespace microdex::station {

struct DdsBridgeTuning {
  bool shared_memory = true;
  bool realtime_threads = true;

  // "all" (the default), "none", or a comma list of "shm" and "rt". Empty when valid;
  // otherwise a reason that names the text.
  static std::string Parse(const std::string& text, DdsBridgeTuning* out);
  std::string Name() const;  // "shm,rt", "shm", "rt" or "none"
  // The options of the bridge's participant: `dds` with the participant profile chosen.
  net::DdsOptions Apply(net::DdsOptions dds) const;
};

}  // namespace microdex::station
