#include "station/dds_device.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <stdexcept>

#include "common/net/convert.h"
#include "common/net/topics.h"
#include "device_forcePubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "station/rt/realtime.h"

namespace microdex::station {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
constexpr int kPublisherPriority = 60;

// Runs on the DDS listener thread: takes every sample addressed to this station and hands the
// latest to the haptic thread. Numbers are passed as they came (a NaN is the guard's to judge).
class DdsDevice::Listener final : public dds::DataReaderListener {
 public:
  explicit Listener(DdsDevice& device) : device_(device) {}
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&msg_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || msg_.station_id().to_string() != device_.station_id_) continue;
      if (!net::FromMsg(msg_, checked_)) {
        device_.invalid_.fetch_add(1, std::memory_order_relaxed);
        if (Finite(msg_)) continue;  // a non-finite one is the guard's fault (kNonFinite)
      }
      BridgeSample s{};
      for (int i = 0; i < 3; ++i) s.p[i] = msg_.p_WT()[i];
      for (int i = 0; i < 4; ++i) s.q[i] = msg_.q_WT()[i];
      s.gripper = msg_.gripper();
      s.buttons = msg_.buttons();
      s.step = msg_.step();
      s.stamp_ns = msg_.stamp_ns();
      s.received_ns = device_.clock_.RealtimeNs();
      device_.OnSample(s);
    }
  }

 private:
  static bool Finite(const msg::DeviceInput& m) {
    bool ok = std::isfinite(m.gripper());
    for (double v : m.p_WT()) ok = ok && std::isfinite(v);
    for (double v : m.q_WT()) ok = ok && std::isfinite(v);
    return ok;
  }

  DdsDevice& device_;
  msg::DeviceInput msg_;
  net::DeviceInput checked_;  // reused: FromMsg's output
};

std::string SecondDeviceKey(const std::string& station_id) {
  if (station_id.size() > 62) {
    throw std::invalid_argument(
        "--station-id: a bimanual station over the DDS bridge: expected "
        "1..62 chars (its second device's key is STATION/2)");
  }
  return station_id + "/2";
}

DdsDevice::DdsDevice(const net::DdsOptions& dds_options, const std::string& station_id,
                     const std::string& session_id, const DeviceMappingDef& mapping,
                     const DeviceGuardDef& guard, const DdsBridgeTuning& tuning)
    : station_id_(station_id),
      session_id_(session_id),
      listener_(std::make_unique<Listener>(*this)),
      guard_(guard),
      mapping_(mapping) {
  // The threads Fast DDS starts for this participant: those that appear while it and its
  // endpoints are created (before the publisher thread is started below).
  const std::vector<int> threads_before = rt::ThreadIds();
  if (tuning.cpu_latency) cpu_latency_ = std::make_unique<CpuLatencyRequest>();
  dds_ = std::make_unique<net::DdsContext>(tuning.Apply(dds_options));
  auto* writer = dds_->CreateWriter<msg::DeviceForcePubSubType>(net::kDeviceForceTopic);
  auto* reader = dds_->CreateReader<msg::DeviceInputPubSubType>(net::kDeviceSampleTopic);
  writer_ = writer;
  reader_ = reader;
  if (tuning.realtime_threads) {
    dds_threads_realtime_ =
        rt::MakeThreadsFifo(rt::ThreadsStartedSince(threads_before), kDdsThreadPriority);
  }
  if (const char* dir = std::getenv(kHopsEnv); dir != nullptr && *dir != '\0') {
    std::string name = station_id_;
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    }
    hops_file_ = std::string(dir) + "/" + name + ".hops.csv";
    hops_.reserve(kMaxHops);
  }
  publisher_ = std::thread([this] { RunPublisher(); });
  reader->set_listener(listener_.get(), dds::StatusMask::data_available());
}

DdsDevice::~DdsDevice() {
  static_cast<dds::DataReader*>(reader_)->set_listener(nullptr);
  stop_.store(true);
  force_event_.Notify();
  publisher_.join();
  dds_.reset();
  WriteHops();
}

void DdsDevice::WriteHops() const {
  if (hops_file_.empty()) return;
  std::FILE* f = std::fopen(hops_file_.c_str(), "w");
  if (f == nullptr) return;  // a diagnostic: the bench reports the file missing
  std::fprintf(f,
               "sample_step,sample_stamp_ns,received_ns,woken_ns,ready_ns,publisher_woken_ns,"
               "write_ns,written_ns\n");
  for (const Hops& h : hops_) {
    std::fprintf(f, "%llu,%lld,%lld,%lld,%lld,%lld,%lld,%lld\n",
                 static_cast<unsigned long long>(h.sample_step),
                 static_cast<long long>(h.sample_stamp_ns), static_cast<long long>(h.received_ns),
                 static_cast<long long>(h.woken_ns), static_cast<long long>(h.ready_ns),
                 static_cast<long long>(h.publisher_woken_ns), static_cast<long long>(h.write_ns),
                 static_cast<long long>(h.written_ns));
  }
  std::fclose(f);
}

void DdsDevice::OnSample(const BridgeSample& s) {
  latest_.back() = s;
  latest_.Publish();
  received_.fetch_add(1, std::memory_order_relaxed);
  sample_event_.Notify();
}

bool DdsDevice::WaitForSample(std::int64_t until_ns) {
  for (;;) {
    const std::uint32_t count = sample_event_.count();
    if (count != sample_seen_) {
      sample_seen_ = count;
      woken_ns_ = clock_.RealtimeNs();
      return true;
    }
    const std::int64_t now = clock_.NowNs();
    if (now >= until_ns) {
      woken_ns_ = clock_.RealtimeNs();
      return false;
    }
    sample_event_.WaitWhile(count, until_ns - now);
  }
}

DeviceSample DdsDevice::Read(std::uint64_t step) {
  step_ = step;
  RawDeviceSample fresh;
  const bool got = latest_.Update();
  if (got) {
    const BridgeSample& b = latest_.front();
    fresh.p_D = Eigen::Vector3d(b.p[0], b.p[1], b.p[2]);
    fresh.q_D = Eigen::Quaterniond(b.q[0], b.q[1], b.q[2], b.q[3]);
    fresh.gripper = b.gripper;
    fresh.buttons = b.buttons;
    fresh.sample_step = b.step;
    fresh.sample_stamp_ns = b.stamp_ns;
    received_ns_ = b.received_ns;
  }
  bool resumed = false;
  raw_ = guard_.Step(got ? &fresh : nullptr, &fault_, &resumed);
  if (got) {  // the echo names the sample this step read, valid or not
    raw_.sample_step = fresh.sample_step;
    raw_.sample_stamp_ns = fresh.sample_stamp_ns;
  }
  if (resumed) mapping_.Recentre();
  DeviceSample out;
  out.X_WT = mapping_.Map(raw_);
  out.gripper = raw_.gripper;
  out.buttons = raw_.buttons;
  out.fault = fault_;
  return out;
}

void DdsDevice::WriteForce(const Eigen::Vector3d& f_T_W) {
  WriteWrench(f_T_W, Eigen::Vector3d::Zero());
}

void DdsDevice::WriteWrench(const Eigen::Vector3d& f_T_W, const Eigen::Vector3d& tau_T_W) {
  const Eigen::Vector3d f_D = mapping_.ForceToDevice(f_T_W);
  const Eigen::Vector3d tau_D = mapping_.TorqueToDevice(tau_T_W);
  ForceOut f{step_,
             raw_.sample_step,
             raw_.sample_stamp_ns,
             {f_D.x(), f_D.y(), f_D.z()},
             {tau_D.x(), tau_D.y(), tau_D.z()},
             static_cast<std::uint8_t>(fault_),
             received_ns_,
             woken_ns_,
             clock_.RealtimeNs()};
  if (!forces_.TryPush(f)) dropped_.fetch_add(1, std::memory_order_relaxed);
  force_event_.Notify();
}

void DdsDevice::RunPublisher() {
  // Just below the haptic thread (80) and above the station's publisher (40): a force waits
  // for nothing else. Without the privilege it runs at normal priority.
  std::string why;
  rt::MakeThisThreadFifo(kPublisherPriority, &why);
  auto* writer = static_cast<dds::DataWriter*>(writer_);
  msg::DeviceForce m;
  m.station_id(station_id_);
  m.session_id(session_id_.substr(0, 64));
  ForceOut f{};
  while (!stop_.load()) {
    const std::uint32_t seen = force_event_.count();
    const std::int64_t woken = clock_.RealtimeNs();
    while (forces_.TryPop(f)) {
      const std::int64_t write_ns = clock_.RealtimeNs();
      m.step(f.step);
      m.stamp_ns(write_ns);
      m.sample_step(f.sample_step);
      m.sample_stamp_ns(f.sample_stamp_ns);
      m.f_D({f.f_D[0], f.f_D[1], f.f_D[2]});
      m.tau_D({f.tau_D[0], f.tau_D[1], f.tau_D[2]});
      m.fault(f.fault);
      writer->write(&m);
      if (!hops_file_.empty() && hops_.size() < kMaxHops) {
        hops_.push_back({f.sample_step, f.sample_stamp_ns, f.received_ns, f.woken_ns, f.ready_ns,
                         woken, write_ns, clock_.RealtimeNs()});
      }
    }
    force_event_.WaitWhile(seen, 100'000'000);
  }
}

}  // namespace microdex::station
