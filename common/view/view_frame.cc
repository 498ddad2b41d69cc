#include "common/view/view_frame.h"

#include <algorithm>
#include <cstring>

namespace microdex::view {
namespace {

void PutU32(std::uint8_t* p, std::uint32_t v) { std::memcpy(p, &v, 4); }
void PutU16(std::uint8_t* p, std::uint16_t v) { std::memcpy(p, &v, 2); }

void Put3(double* s, int at, const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i) s[at + i] = v[i];
}
void PutQ(double* s, int at, const Eigen::Quaterniond& q) {
  s[at] = q.w();
  s[at + 1] = q.x();
  s[at + 2] = q.y();
  s[at + 3] = q.z();
}

}  // namespace

void EncodeFrame(const FrameSource& src, FrameBytes& out) {
  std::array<double, kScalarCount> s{};
  std::uint16_t flags = 0;
  if (src.tool != nullptr) {
    const net::ToolState& t = *src.tool;
    s[kStampMs] = static_cast<double>(t.header.stamp_ns) * 1e-6;
    s[kStep] = static_cast<double>(t.header.step);
    Put3(s.data(), kToolP, t.p_WT);
    PutQ(s.data(), kToolQ, t.q_WT);
    Put3(s.data(), kToolForce, t.f_T_W);
    s[kActiveCues] = t.active_cues;
    s[kTremorRms] = t.tremor_rms_m;
    if (t.has_second_tool) {
      flags |= kHasSecondTool;
      Put3(s.data(), kTool2P, t.p_WT2);
      PutQ(s.data(), kTool2Q, t.q_WT2);
      Put3(s.data(), kTool2Force, t.f_T2_W);
    }
    const int stitches = std::clamp(t.stitch_count, 0, static_cast<int>(net::kMaxStitches));
    s[kStitchCount] = stitches;
    for (int i = 0; i < stitches; ++i) {
      s[kStitchAzimuth + i] = t.stitch_azimuth_rad[static_cast<std::size_t>(i)];
      s[kStitchBite + i] = t.stitch_bite_m[static_cast<std::size_t>(i)];
    }
  } else {
    s[kToolQ] = 1;
  }
  if ((flags & kHasSecondTool) == 0) s[kTool2Q] = 1;
  s[kSentMs] = static_cast<double>(src.sent_realtime_ns) * 1e-6;
  if (src.needle != nullptr) {
    flags |= kHasNeedle;
    Put3(s.data(), kNeedleP, src.needle->p_WN);
    PutQ(s.data(), kNeedleQ, src.needle->q_WN);
    s[kClearance] = src.needle->clearance_m;
    s[kContact] = src.needle->contact ? 1 : 0;
  }
  std::uint32_t thread_nodes = 0;
  if (src.thread != nullptr) {
    flags |= kHasThread;
    thread_nodes = static_cast<std::uint32_t>(
        std::min<std::size_t>(src.thread->nodes.size(), kMaxFrameThreadNodes));
    s[kThreadStrain] = src.thread->max_strain;
    s[kGraspedNode] = src.thread->grasped_node;
  }
  std::size_t tissue_values = 0;
  if (src.tissue != nullptr) {
    const net::TissueState& t = *src.tissue;
    tissue_values = std::min<std::size_t>(
        {t.displacement_m.size(), std::size_t{t.nodes_x} * t.nodes_y, kMaxFrameTissueNodes});
    if (tissue_values == std::size_t{t.nodes_x} * t.nodes_y && tissue_values > 0) {
      flags |= kHasTissue;
      s[kTissueNodesX] = t.nodes_x;
      s[kTissueNodesY] = t.nodes_y;
      s[kTissueDepth] = t.max_displacement_m;
      Put3(s.data(), kTissueP, t.p_WS);
      PutQ(s.data(), kTissueQ, t.q_WS);
      s[kTissueLx] = t.length_x_m;
      s[kTissueLy] = t.length_y_m;
    } else {
      tissue_values = 0;  // inconsistent sizes: drawn without the field
    }
  }
  if (src.score != nullptr) {
    flags |= kHasScore;
    s[kScore] = src.score->score;
    s[kProgress] = src.score->progress;
    s[kOutcome] = src.score->outcome;
  }
  if (src.telemetry != nullptr) {
    flags |= kHasTelemetry;
    s[kPeriodP99Ms] = src.telemetry->period_p99_s * 1e3;
    s[kOverruns] = static_cast<double>(src.telemetry->overruns);
  }
  s[kPresence] = src.presence;
  s[kToolAgeMs] = src.tool_age_ms;

  std::uint8_t* p = out.bytes.data();
  PutU32(p, kFrameMagic);
  PutU16(p + 4, kFrameVersion);
  PutU16(p + 6, flags);
  PutU32(p + 8, src.slot);
  PutU32(p + 12, thread_nodes);
  p += kFrameHeaderBytes;
  std::memcpy(p, s.data(), sizeof s);
  p += sizeof s;
  for (std::uint32_t i = 0; i < thread_nodes; ++i) {
    const float xyz[3] = {static_cast<float>(src.thread->nodes[i].x()),
                          static_cast<float>(src.thread->nodes[i].y()),
                          static_cast<float>(src.thread->nodes[i].z())};
    std::memcpy(p, xyz, sizeof xyz);
    p += sizeof xyz;
  }
  if (tissue_values > 0) {
    std::memcpy(p, src.tissue->displacement_m.data(), tissue_values * sizeof(float));
    p += tissue_values * sizeof(float);
  }
  if (src.overlay != nullptr) {
    const cues::CueOverlay& o = *src.overlay;
    const int lines = std::clamp(o.polyline_count, 0, cues::kMaxOverlayPolylines);
    const int labels = std::clamp(o.label_count, 0, cues::kMaxOverlayLabels);
    auto put = [&p](double v) {
      const auto f = static_cast<float>(v);
      std::memcpy(p, &f, 4);
      p += 4;
    };
    put(lines);
    put(labels);
    for (int i = 0; i < lines; ++i) {
      const cues::OverlayPolyline& l = o.polylines[static_cast<std::size_t>(i)];
      const int n = std::clamp(l.count, 0, cues::kMaxOverlayPoints);
      put(static_cast<double>(l.role));
      put(l.colour.r);
      put(l.colour.g);
      put(l.colour.b);
      put(l.colour.a);
      put(l.width_m);
      put(n);
      for (int k = 0; k < n; ++k) {
        for (int c = 0; c < 3; ++c) put(l.p_W[static_cast<std::size_t>(k)][c]);
      }
    }
    for (int i = 0; i < labels; ++i) {
      const cues::OverlayLabel& l = o.labels[static_cast<std::size_t>(i)];
      put(static_cast<double>(l.role));
      put(l.colour.r);
      put(l.colour.g);
      put(l.colour.b);
      put(l.colour.a);
      for (int c = 0; c < 3; ++c) put(l.p_W[c]);
      std::array<char, kOverlayLabelBytes> text{};
      std::memcpy(text.data(), l.text.data(),
                  std::min(strnlen(l.text.data(), l.text.size()), kOverlayLabelBytes - 1));
      std::memcpy(p, text.data(), text.size());
      p += text.size();
    }
    flags |= kHasOverlay;
    PutU16(out.bytes.data() + 6, flags);
  }
  out.size = static_cast<std::uint32_t>(p - out.bytes.data());
}

}  // namespace microdex::view
