#include "station/dds_bridge_tuning.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <utility>

#include "common/net/topics.h"

namespace microdex::station {

std::string DdsBridgeTuning::Parse(const std::string& text, DdsBridgeTuning* out) {
  if (text == "all") {
    *out = DdsBridgeTuning{};
    return {};
  }
  DdsBridgeTuning t{false, false, false};
  std::string expected = "'" + text + "': expected all, none or a comma list of shm, rt, cpu";
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
      } else if (part == "cpu") {
        t.cpu_latency = true;
      } else {
        return expected;
      }
    }
    if (parts == 0) return expected;
  }
  *out = t;
  return {};
}

std::string DdsBridgeTuning::Name() const {
  std::string name;
  for (const auto& [on, part] : {std::pair{shared_memory, "shm"}, std::pair{realtime_threads, "rt"},
                                 std::pair{cpu_latency, "cpu"}}) {
    if (!on) continue;
    if (!name.empty()) name += ',';
    name += part;
  }
  return name.empty() ? "none" : name;
}

CpuLatencyRequest::CpuLatencyRequest() {
  fd_ = open("/dev/cpu_dma_latency", O_RDWR | O_CLOEXEC);
  if (fd_ < 0) {
    why_not_ = std::string("/dev/cpu_dma_latency: ") + std::strerror(errno);
    return;
  }
  const std::int32_t zero_us = 0;
  if (write(fd_, &zero_us, sizeof zero_us) != static_cast<ssize_t>(sizeof zero_us)) {
    why_not_ = std::string("/dev/cpu_dma_latency: ") + std::strerror(errno);
    close(fd_);
    fd_ = -1;
  }
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) close(fd_);
}

net::DdsOptions DdsBridgeTuning::Apply(net::DdsOptions dds) const {
  dds.participant_profile = shared_memory ? net::kDeviceBridgeParticipantProfile : "";
  return dds;
}

}  // namespace microdex::station
