#include "station/device_driver.h"

#include <algorithm>
#include <cmath>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "common/net/topics.h"
#include "device_forcePubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "station/playback_device.h"
#include "station/rt/clock.h"
#include "station/rt/realtime.h"

namespace microdex::station {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
constexpr double kPi = 3.14159265358979323846;

class ForceListener final : public dds::DataReaderListener {
 public:
  ForceListener(std::string station_id, std::size_t capacity)
      : station_id_(std::move(station_id)), answered_(capacity, 0) {
    stats_.round_trip_us.reserve(capacity);
    stats_.hops.reserve(capacity);
  }
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&msg_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || msg_.station_id().to_string() != station_id_) continue;
      const std::int64_t now = clock_.RealtimeNs();
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.forces;
      if (msg_.fault() != 0) ++stats_.fault_forces;
      const double f = std::sqrt(msg_.f_D()[0] * msg_.f_D()[0] + msg_.f_D()[1] * msg_.f_D()[1] +
                                 msg_.f_D()[2] * msg_.f_D()[2]);
      stats_.force_max_N = std::max(stats_.force_max_N, f);
      const double tau =
          std::sqrt(msg_.tau_D()[0] * msg_.tau_D()[0] + msg_.tau_D()[1] * msg_.tau_D()[1] +
                    msg_.tau_D()[2] * msg_.tau_D()[2]);
      stats_.torque_max_Nm = std::max(stats_.torque_max_Nm, tau);
      const std::uint64_t k = msg_.sample_step();
      if (k < answered_.size() && !answered_[k] && msg_.sample_stamp_ns() > 0) {
        answered_[k] = 1;
        ++stats_.answered;
        stats_.round_trip_us.push_back(static_cast<double>(now - msg_.sample_stamp_ns()) * 1e-3);
        stats_.hops.push_back({k, msg_.sample_stamp_ns(), 0, msg_.stamp_ns(), now});
      }
    }
  }
  DriverStats Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_;
  }

 private:
  std::string station_id_;
  rt::MonotonicClock clock_;
  msg::DeviceForce msg_;
  std::mutex mutex_;
  std::vector<std::uint8_t> answered_;
  DriverStats stats_;
};

}  // namespace

std::string DeviceDriverDef::Validate() const {
  if (station_id.empty() || station_id.size() > 64) return "station-id: expected 1..64 chars";
  if (!(rate_hz >= 10 && rate_hz <= 10000)) return "rate: expected 10..10000 Hz";
  if (!(duration_s > 0 && duration_s <= 3600)) return "duration: expected 0 < S <= 3600";
  if (!(fault_at_s >= 0 && fault_for_s > 0 && std::isfinite(fault_at_s + fault_for_s))) {
    return "fault-at / fault-for: expected >= 0 and > 0 s";
  }
  if (!(circle_radius_m >= 0 && circle_radius_m <= 0.2)) return "radius: expected 0..0.2 m";
  return {};
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(
      std::llround(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1)));
  return v[i];
}

DriverStats RunDeviceDriver(const net::DdsOptions& dds_options, const DeviceDriverDef& def,
                            const std::atomic<bool>& stop) {
  if (const std::string why = def.Validate(); !why.empty()) throw std::runtime_error(why);
  std::unique_ptr<PlaybackDevice> csv;
  if (!def.csv.empty()) csv = std::make_unique<PlaybackDevice>(def.csv);
  const std::vector<int> threads_before = rt::ThreadIds();
  std::optional<CpuLatencyRequest> cpu_latency;
  if (def.tuning.cpu_latency) cpu_latency.emplace();
  net::DdsContext ctx(def.tuning.Apply(dds_options));
  dds::DataWriter* writer = ctx.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceSampleTopic);
  dds::DataReader* reader = ctx.CreateReader<msg::DeviceForcePubSubType>(net::kDeviceForceTopic);
  const int dds_threads_realtime =
      def.tuning.realtime_threads
          ? rt::MakeThreadsFifo(rt::ThreadsStartedSince(threads_before), kDriverDdsThreadPriority)
          : 0;
  const auto total = static_cast<std::uint64_t>(std::llround(def.duration_s * def.rate_hz));
  ForceListener listener(def.station_id, total + 1);
  reader->set_listener(&listener, dds::StatusMask::data_available());

  rt::MonotonicClock clock;
  // Wait for the station's bridge (its reader and writer).
  const std::int64_t give_up =
      clock.NowNs() + static_cast<std::int64_t>(def.discovery_timeout_s * 1e9);
  bool matched = false;
  while (!stop.load() && clock.NowNs() < give_up) {
    dds::PublicationMatchedStatus pm;
    dds::SubscriptionMatchedStatus sm;
    writer->get_publication_matched_status(pm);
    reader->get_subscription_matched_status(sm);
    if (pm.current_count > 0 && sm.current_count > 0) {
      matched = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // A driver's servo loop runs at real-time priority where it may (as the station's haptic
  // thread does); otherwise at normal priority.
  std::string why;
  const bool fifo = rt::MakeThisThreadFifo(kDriverPriority, &why);
  msg::DeviceInput m;
  m.station_id(def.station_id);
  m.session_id("driver");
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / def.rate_hz));
  std::int64_t deadline = clock.NowNs();
  std::uint64_t sent = 0;
  std::vector<std::int64_t> write_returned(total + 1, 0);
  for (std::uint64_t k = 1; matched && k <= total && !stop.load(); ++k) {
    deadline += period_ns;
    clock.SleepUntilNs(deadline);
    const double t = static_cast<double>(k) / def.rate_hz;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    double gripper = 0;
    std::uint32_t buttons = 0;
    if (csv) {
      const DeviceSample s = csv->Read(k - 1);
      p = s.X_WT.translation();
      q = Eigen::Quaterniond(s.X_WT.linear());
      gripper = s.gripper;
      buttons = s.buttons;
    } else {
      const double a = 2 * kPi * def.circle_hz * t;
      p = def.circle_radius_m * Eigen::Vector3d(std::cos(a) - 1, std::sin(a), 0);
    }
    const bool in_fault = t >= def.fault_at_s && t < def.fault_at_s + def.fault_for_s;
    if (in_fault && def.fault == DriverFault::kStop) continue;
    if (in_fault && def.fault == DriverFault::kNaN)
      p.x() = std::numeric_limits<double>::quiet_NaN();
    if (in_fault && def.fault == DriverFault::kJump) p.x() += 0.05;
    m.step(k);
    m.stamp_ns(clock.RealtimeNs());
    m.p_WT({p.x(), p.y(), p.z()});
    m.q_WT({q.w(), q.x(), q.y(), q.z()});
    m.gripper(gripper);
    m.buttons(buttons);
    writer->write(&m);
    write_returned[k] = clock.RealtimeNs();
    ++sent;
  }
  // The last forces still on their way.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  reader->set_listener(nullptr);
  DriverStats stats = listener.Take();
  stats.matched = matched;
  stats.realtime = fifo;
  stats.dds_threads_realtime = dds_threads_realtime;
  stats.sent = sent;
  stats.lost = sent - std::min(sent, stats.answered);
  for (DriverHop& h : stats.hops) {
    if (h.sample_step < write_returned.size()) h.write_returned_ns = write_returned[h.sample_step];
  }
  return stats;
}

}  // namespace microdex::station
