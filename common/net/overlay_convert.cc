#include "common/net/overlay_convert.h"

#include <cmath>

#include "common/base/check.h"

namespace microdex::net {
namespace {

void ColourToMsg(const cues::Rgba& c, std::array<float, 4>& out) { out = {c.r, c.g, c.b, c.a}; }

bool ColourFromMsg(const std::array<float, 4>& in, cues::Rgba& c) {
  for (float v : in) {
    if (!(v >= 0 && v <= 1)) return false;
  }
  c = {in[0], in[1], in[2], in[3]};
  return true;
}

bool RoleFromMsg(std::uint8_t in, cues::OverlayRole& role) {
  if (in > static_cast<std::uint8_t>(cues::OverlayRole::kPrediction)) return false;
  role = static_cast<cues::OverlayRole>(in);
  return true;
}

bool Fail(std::string* why, const std::string& reason) {
  if (why != nullptr) *why = reason;
  return false;
}

}  // namespace

void ToMsg(const Header& header, std::uint32_t active, const cues::CueOverlay& in,
           msg::CueOverlay& out) {
  MICRODEX_CHECK(header.station_id.size() <= kMaxIdLength);
  MICRODEX_CHECK(header.session_id.size() <= kMaxIdLength);
  out.station_id(header.station_id);
  out.session_id(header.session_id);
  out.step(header.step);
  out.stamp_ns(header.stamp_ns);
  out.active_cues(active);
  out.polylines().resize(static_cast<std::size_t>(in.polyline_count));
  for (int i = 0; i < in.polyline_count; ++i) {
    const cues::OverlayPolyline& p = in.polylines[i];
    msg::OverlayPolyline& m = out.polylines()[i];
    m.role(static_cast<std::uint8_t>(p.role));
    ColourToMsg(p.colour, m.rgba());
    m.width_m(p.width_m);
    m.p_W().resize(3 * static_cast<std::size_t>(p.count));
    for (int k = 0; k < p.count; ++k) {
      for (int j = 0; j < 3; ++j) m.p_W()[3 * k + j] = p.p_W[k][j];
    }
  }
  out.labels().resize(static_cast<std::size_t>(in.label_count));
  for (int i = 0; i < in.label_count; ++i) {
    const cues::OverlayLabel& l = in.labels[i];
    msg::OverlayLabel& m = out.labels()[i];
    m.role(static_cast<std::uint8_t>(l.role));
    ColourToMsg(l.colour, m.rgba());
    m.p_W({l.p_W.x(), l.p_W.y(), l.p_W.z()});
    m.text(std::string(l.text.data()));
  }
}

bool FromMsg(const msg::CueOverlay& in, Header& header, std::uint32_t& active,
             cues::CueOverlay& out, std::string* why) {
  if (in.station_id().size() > kMaxIdLength) return Fail(why, "station_id: too long");
  header.station_id = in.station_id().to_string();
  header.session_id = in.session_id().to_string();
  header.step = in.step();
  header.stamp_ns = in.stamp_ns();
  active = in.active_cues();
  out.step = in.step();
  if (in.polylines().size() > cues::kMaxOverlayPolylines) return Fail(why, "polylines: too many");
  if (in.labels().size() > cues::kMaxOverlayLabels) return Fail(why, "labels: too many");
  out.polyline_count = static_cast<int>(in.polylines().size());
  for (int i = 0; i < out.polyline_count; ++i) {
    const msg::OverlayPolyline& m = in.polylines()[i];
    cues::OverlayPolyline& p = out.polylines[i];
    if (!RoleFromMsg(m.role(), p.role)) return Fail(why, "polylines[].role: names no role");
    if (!ColourFromMsg(m.rgba(), p.colour)) return Fail(why, "polylines[].rgba: expected 0..1");
    if (!std::isfinite(m.width_m()) || m.width_m() < 0) {
      return Fail(why, "polylines[].width_m: expected a finite number >= 0");
    }
    p.width_m = m.width_m();
    if (m.p_W().size() % 3 != 0 || m.p_W().size() > 3 * cues::kMaxOverlayPoints) {
      return Fail(why, "polylines[].p_W: expected x y z triples, at most 64 points");
    }
    p.count = static_cast<int>(m.p_W().size() / 3);
    for (int k = 0; k < p.count; ++k) {
      p.p_W[k] = {m.p_W()[3 * k], m.p_W()[3 * k + 1], m.p_W()[3 * k + 2]};
      if (!p.p_W[k].allFinite()) return Fail(why, "polylines[].p_W: expected finite numbers");
    }
  }
  out.label_count = static_cast<int>(in.labels().size());
  for (int i = 0; i < out.label_count; ++i) {
    const msg::OverlayLabel& m = in.labels()[i];
    cues::OverlayLabel& l = out.labels[i];
    if (!RoleFromMsg(m.role(), l.role)) return Fail(why, "labels[].role: names no role");
    if (!ColourFromMsg(m.rgba(), l.colour)) return Fail(why, "labels[].rgba: expected 0..1");
    l.p_W = {m.p_W()[0], m.p_W()[1], m.p_W()[2]};
    if (!l.p_W.allFinite()) return Fail(why, "labels[].p_W: expected finite numbers");
    const std::string text = m.text().to_string();
    if (text.size() > cues::kMaxOverlayLabelLength) return Fail(why, "labels[].text: too long");
    l.text.fill('\0');
    text.copy(l.text.data(), text.size());
  }
  return true;
}

}  // namespace microdex::net
