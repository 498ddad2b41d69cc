#include "instructor/replay_export.h"

#include <sys/stat.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "common/record/recorded_topics.h"
#include "cue_commandPubSubTypes.h"
#include "cue_overlayPubSubTypes.h"
#include "device_forcePubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "instructor/recorded_sample.h"
#include "needle_statePubSubTypes.h"
#include "scorePubSubTypes.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
#include "telemetryPubSubTypes.h"
#include "thread_statePubSubTypes.h"
#include "tissue_statePubSubTypes.h"
#include "tool_statePubSubTypes.h"

namespace microdex::instructor {
namespace {

using record::TopicIndex;

// Round-trip precision for doubles; text fields quoted.
class Row {
 public:
  Row& operator<<(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return Add(buf);
  }
  Row& operator<<(std::uint64_t v) { return Add(std::to_string(v)); }
  Row& operator<<(std::int64_t v) { return Add(std::to_string(v)); }
  Row& operator<<(std::uint32_t v) { return Add(std::to_string(v)); }
  Row& operator<<(std::int32_t v) { return Add(std::to_string(v)); }
  Row& operator<<(std::uint8_t v) { return Add(std::to_string(v)); }
  template <std::size_t N>
  Row& operator<<(const eprosima::fastrtps::fixed_string<N>& s) {
    return *this << s.to_string();
  }
  Row& operator<<(const std::string& s) {
    std::string q;
    q.reserve(s.size() + 2);
    q.push_back('"');
    for (char c : s) {
      if (c == '"') q.push_back('"');
      q.push_back(c);
    }
    q.push_back('"');
    return Add(q);
  }
  template <std::size_t N>
  Row& operator<<(const std::array<double, N>& a) {
    for (double v : a) *this << v;
    return *this;
  }
  std::string str() const { return text_; }

 private:
  Row& Add(const std::string& s) {
    if (!text_.empty()) text_ += ',';
    text_ += s;
    return *this;
  }
  std::string text_;
};

constexpr const char* kCommonHeader = "station,session,receive_ns,source_ns,sequence,step";

// The topic's extra columns and one row of them; false when the bytes do not decode.
struct TopicCsv {
  const char* header;
  bool (*row)(std::span<const std::uint8_t>, Row&);
};

const TopicCsv kTopicCsv[record::kTopicCount] = {
    {"stamp_ns,trainee,scene,modules,build,haptic_rate_hz,mirror_rate_hz,skill,device,seed",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::StationInfo m;
       if (!DecodeSample<msg::StationInfoPubSubType>(b, m)) return false;
       std::string modules;
       for (const auto& n : m.modules()) {
         if (!modules.empty()) modules.push_back(' ');
         modules.append(n.name().c_str());
       }
       r << std::int64_t{m.stamp_ns()} << m.trainee() << m.scene() << modules << m.build()
         << m.haptic_rate_hz() << m.mirror_rate_hz() << m.skill() << m.device()
         << std::uint64_t{m.seed()};
       return true;
     }},
    {"stamp_ns,px,py,pz,qw,qx,qy,qz,gripper,buttons,state_hash",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::DeviceInput m;
       if (!DecodeSample<msg::DeviceInputPubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << m.p_WT() << m.q_WT() << m.gripper()
         << std::uint32_t{m.buttons()} << std::uint64_t{m.state_hash()};
       return true;
     }},
    {"stamp_ns,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tremor_rms_m,active_cues",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::ToolState m;
       if (!DecodeSample<msg::ToolStatePubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << m.p_WT() << m.q_WT() << m.f_T_W() << m.tremor_rms_m()
         << std::uint32_t{m.active_cues()};
       return true;
     }},
    {"stamp_ns,px,py,pz,qw,qx,qy,qz,clearance_m,contact,s_rad,dx,dy,dz,bx,by,bz,status",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::NeedleState m;
       if (!DecodeSample<msg::NeedleStatePubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << m.p_WN() << m.q_WN() << m.clearance_m()
         << std::uint8_t{m.contact()} << m.s_rad() << m.p_WD() << m.p_WB()
         << static_cast<std::uint32_t>(m.status());
       return true;
     }},
    {"stamp_ns,nodes,knot,max_strain,grasped_node,fx,fy,fz",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::ThreadState m;
       if (!DecodeSample<msg::ThreadStatePubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << static_cast<std::uint64_t>(m.nodes().size()) << m.knot()
         << m.max_strain() << std::int32_t{m.grasped_node()} << m.f_T_W();
       return true;
     }},
    {"stamp_ns,nodes_x,nodes_y,mesh_revision,unknowns,max_displacement_m,status",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::TissueState m;
       if (!DecodeSample<msg::TissueStatePubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << std::uint32_t{m.nodes_x()} << std::uint32_t{m.nodes_y()}
         << std::uint32_t{m.mesh_revision()} << std::uint32_t{m.unknowns()}
         << m.max_displacement_m() << static_cast<std::uint32_t>(m.status());
       return true;
     }},
    {"stamp_ns,ticks,period_mean_s,period_p99_s,period_max_s,overruns,ring_dropped,realtime,"
     "has_state_hash,state_hash_step,state_hash,cues_invalid,device_samples_invalid",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::Telemetry m;
       if (!DecodeSample<msg::TelemetryPubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << std::uint64_t{m.ticks()} << m.period_mean_s()
         << m.period_p99_s() << m.period_max_s() << std::uint64_t{m.overruns()}
         << std::uint64_t{m.ring_dropped()} << std::uint8_t{m.realtime()}
         << std::uint8_t{m.has_state_hash()} << std::uint64_t{m.state_hash_step()}
         << std::uint64_t{m.state_hash()} << std::uint64_t{m.cues_invalid()}
         << std::uint64_t{m.device_samples_invalid()};
       return true;
     }},
    {"stamp_ns,cue_id,kind,param,issuer",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::CueCommand m;
       if (!DecodeSample<msg::CueCommandPubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << std::uint64_t{m.cue_id()}
         << static_cast<std::uint32_t>(m.kind()) << m.param() << m.issuer();
       return true;
     }},
    {"stamp_ns,kind,cue_id,value,text",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::TaskEvent m;
       if (!DecodeSample<msg::TaskEventPubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << static_cast<std::uint32_t>(m.kind())
         << std::uint64_t{m.cue_id()} << m.value() << m.text();
       return true;
     }},
    {"stamp_ns,is_final,score,task,outcome,progress,duration_s,time_in_contact_s,contacts,"
     "tremor_rms_m,path_length_m,deviation_mean_m",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::Score m;
       if (!DecodeSample<msg::ScorePubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << std::uint8_t{m.is_final()} << m.score() << m.task()
         << std::uint8_t{m.outcome()} << m.progress() << m.duration_s() << m.time_in_contact_s()
         << std::uint32_t{m.contacts()} << m.tremor_rms_m() << m.path_length_m()
         << m.deviation_mean_m();
       return true;
     }},
    {"stamp_ns,active_cues,polylines,points,labels",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::CueOverlay m;
       if (!DecodeSample<msg::CueOverlayPubSubType>(b, m)) return false;
       std::uint64_t points = 0;
       for (const auto& p : m.polylines()) points += p.p_W().size() / 3;
       r << std::int64_t{m.stamp_ns()} << std::uint32_t{m.active_cues()}
         << static_cast<std::uint64_t>(m.polylines().size()) << points
         << static_cast<std::uint64_t>(m.labels().size());
       return true;
     }},
    {"stamp_ns,sample_step,sample_stamp_ns,fx,fy,fz,tx,ty,tz,fault",
     [](std::span<const std::uint8_t> b, Row& r) {
       msg::DeviceForce m;
       if (!DecodeSample<msg::DeviceForcePubSubType>(b, m)) return false;
       r << std::int64_t{m.stamp_ns()} << std::uint64_t{m.sample_step()}
         << std::int64_t{m.sample_stamp_ns()} << m.f_D() << m.tau_D() << std::uint8_t{m.fault()};
       return true;
     }},
};

std::string FileName(const std::string& topic) {
  std::string name = topic;
  if (const auto slash = name.rfind('/'); slash != std::string::npos) name.erase(0, slash + 1);
  return name + ".csv";
}

}  // namespace

std::size_t ExportCsv(record::SessionReader& reader, const std::string& dir) {
  ::mkdir(dir.c_str(), 0755);
  std::size_t rows = 0;
  for (int t = 0; t < record::kTopicCount; ++t) {
    const std::string path =
        dir + "/" + FileName(record::KnownTopics()[static_cast<std::size_t>(t)].name);
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot write");
    f << kCommonHeader << ',' << kTopicCsv[t].header << '\n';
    std::size_t bad = 0;
    reader.ForEach({t}, [&](const record::MessageView& m) {
      Row r;
      r << std::string(m.station) << std::string(m.session) << m.receive_ns << m.source_ns
        << m.sequence << m.step;
      if (!kTopicCsv[t].row(m.cdr, r)) {
        ++bad;
        return true;
      }
      f << r.str() << '\n';
      ++rows;
      return true;
    });
    if (!f) throw std::runtime_error(path + ": write failed");
    if (bad > 0) {
      throw std::runtime_error(reader.path() + ": " + std::to_string(bad) + " " +
                               record::KnownTopics()[static_cast<std::size_t>(t)].name +
                               " samples do not decode (left out of " + path + ")");
    }
  }
  return rows;
}

std::string SessionSummaryMarkdown(record::SessionReader& reader) {
  struct StationSummary {
    msg::StationInfo info;
    bool have_info = false;
    msg::Score score;
    bool have_score = false;
    std::uint64_t inputs = 0;
    std::map<std::string, int> events;
    std::vector<std::string> cues;
  };
  std::map<std::string, StationSummary> st;
  reader.ForEach({}, [&](const record::MessageView& m) {
    StationSummary& s = st[std::string(m.station)];
    switch (static_cast<TopicIndex>(m.topic)) {
      case TopicIndex::kStationInfo:
        s.have_info = DecodeSample<msg::StationInfoPubSubType>(m.cdr, s.info) || s.have_info;
        break;
      case TopicIndex::kDeviceInput:
        ++s.inputs;
        break;
      case TopicIndex::kScore: {
        msg::Score sc;
        if (DecodeSample<msg::ScorePubSubType>(m.cdr, sc)) {
          s.score = sc;
          s.have_score = true;
        }
        break;
      }
      case TopicIndex::kTaskEvent: {
        msg::TaskEvent e;
        if (!DecodeSample<msg::TaskEventPubSubType>(m.cdr, e)) break;
        static const char* kNames[] = {"task start",   "task end",      "cue applied",
                                       "cue rejected", "contact begin", "contact end"};
        const auto k = static_cast<std::size_t>(e.kind());
        ++s.events[k < 6 ? kNames[k] : "other"];
        if (e.kind() == msg::EVENT_CUE_APPLIED) {
          char cue[160];
          std::snprintf(cue, sizeof cue, "%s %g at step %llu", e.text().c_str(), e.value(),
                        static_cast<unsigned long long>(e.step()));
          s.cues.emplace_back(cue);
        }
        break;
      }
      default:
        break;
    }
    return true;
  });
  std::ostringstream md;
  const auto [t0, t1] = reader.TimeRange();
  md << "# Session summary\n\n";
  md << "- file: `" << reader.path() << "`\n";
  for (const auto& [k, v] : reader.metadata()) md << "- " << k << ": " << v << "\n";
  char dur[64];
  std::snprintf(dur, sizeof dur, "%.1f s", static_cast<double>(t1 - t0) * 1e-9);
  md << "- recorded: " << dur << "\n\n";
  md << "| station | trainee | scene | seed | steps | score | task | outcome | progress |\n";
  md << "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [id, s] : st) {
    if (!s.have_info && s.inputs == 0) continue;
    char score[32] = "-", progress[32] = "-";
    const char* outcome = "-";
    if (s.have_score) {
      std::snprintf(score, sizeof score, "%.1f%s", s.score.score(),
                    s.score.is_final() ? "" : " (live)");
      std::snprintf(progress, sizeof progress, "%.0f %%", 100 * s.score.progress());
      outcome = s.score.outcome() == 1 ? "completed"
                                       : (s.score.outcome() == 2 ? "time limit" : "running");
    }
    md << "| " << id << " | " << (s.have_info ? s.info.trainee().c_str() : "?") << " | "
       << (s.have_info ? s.info.scene().c_str() : "?") << " | " << (s.have_info ? s.info.seed() : 0)
       << " | " << s.inputs << " | " << score << " | "
       << (s.have_score ? s.score.task().c_str() : "-") << " | " << outcome << " | " << progress
       << " |\n";
  }
  for (const auto& [id, s] : st) {
    if (!s.have_info && s.inputs == 0) continue;
    md << "\n## " << id << "\n\n";
    if (s.have_score && !s.score.terms().empty()) {
      md << "| term | value | limit | weight | points |\n|---|---|---|---|---|\n";
      for (const auto& t : s.score.terms()) {
        char line[256];
        std::snprintf(line, sizeof line, "| %s | %.6g | %.6g | %.3g | %.3g |\n", t.metric().c_str(),
                      t.value(), t.limit(), t.weight(), t.points());
        md << line;
      }
      md << "\n";
    }
    md << "Events:";
    if (s.events.empty()) md << " none";
    for (const auto& [k, n] : s.events) md << " " << k << " " << n << ";";
    md << "\n";
    for (const auto& c : s.cues) md << "- cue " << c << "\n";
  }
  return md.str();
}

}  // namespace microdex::instructor
