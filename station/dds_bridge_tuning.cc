#include "station/dds_bridge_tuning.h"

#include <sstream>

#include "common/net/topics.h"

namespace microdex::station {

std::string DdsBridgeTuning::Parse(const std::string& text, DdsBridgeTuning* out) {
  if (text == "all") {
    *out = DdsBridgeTuning{};
    return {};
  }
  DdsBridgeTuning t{false, false};
  if (text != "none") {
    std::istringstream in(text);
    std::string part;
    int parts = 0;
    while (std::getline(in, part, ',')) {
      ++parts;
      if (part == "shm") {
        t.shared_memory = true;
      } else if (part == "rt") {
        t.realtime_threads = true;
      } else {
        return "'" + text + "': expected all, none or a comma list of shm, rt";
      }
    }
    if (parts == 0) return "'" + text + "': expected all, none or a comma list of shm, rt";
  }
  *out = t;
  return {};
}

std::string DdsBridgeTuning::Name() const {
  if (shared_memory && realtime_threads) return "shm,rt";
  if (shared_memory) return "shm";
  if (realtime_threads) return "rt";
  return "none";
}

net::DdsOptions DdsBridgeTuning::Apply(net::DdsOptions dds) const {
  dds.participant_profile = shared_memory ? net::kDeviceBridgeParticipantProfile : "";
  return dds;
}

}  // namespace microdex::station
