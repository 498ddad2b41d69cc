// The CueOverlay topic: an overlay survives ToMsg → FromMsg; a hostile sample (a NaN point, a
// colour out of 0..1, a role that names none, a point list that is not x y z triples, too many
// points) is rejected with the field named.
#include "common/net/overlay_convert.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace microdex::net {
namespace {

cues::CueOverlay Sample() {
  cues::OverlayInput in;
  in.active =
      cues::CueBit(cues::CueKind::kVisualPath) | cues::CueBit(cues::CueKind::kVisualDeviation);
  in.param[static_cast<std::size_t>(cues::CueKind::kVisualPath)] = 50e-6;
  in.tolerance_m = 0.5e-3;
  in.p_WT = Eigen::Vector3d(5.2e-3, 0, 0);
  in.p_W_nearest = Eigen::Vector3d(5e-3, 0, 0);
  in.deviation_m = 0.2e-3;
  cues::CueOverlay o;
  cues::CalcCueOverlay(in, o);
  return o;
}

TEST(OverlayConvert, RoundTrip) {
  const cues::CueOverlay in = Sample();
  ASSERT_EQ(in.polyline_count, 2);
  ASSERT_EQ(in.label_count, 1);
  msg::CueOverlay m;
  ToMsg({"st-1", "session", 42, 7}, 0x11, in, m);
  Header h;
  std::uint32_t active = 0;
  cues::CueOverlay out;
  std::string why;
  ASSERT_TRUE(FromMsg(m, h, active, out, &why)) << why;
  EXPECT_EQ(h.station_id, "st-1");
  EXPECT_EQ(h.step, 42u);
  EXPECT_EQ(active, 0x11u);
  ASSERT_EQ(out.polyline_count, in.polyline_count);
  for (int i = 0; i < in.polyline_count; ++i) {
    EXPECT_EQ(out.polylines[i].role, in.polylines[i].role);
    EXPECT_EQ(out.polylines[i].colour.g, in.polylines[i].colour.g);
    EXPECT_EQ(out.polylines[i].width_m, in.polylines[i].width_m);
    ASSERT_EQ(out.polylines[i].count, in.polylines[i].count);
    for (int k = 0; k < in.polylines[i].count; ++k) {
      EXPECT_EQ(out.polylines[i].p_W[k], in.polylines[i].p_W[k]);
    }
  }
  EXPECT_EQ(std::string(out.labels[0].text.data()), std::string(in.labels[0].text.data()));
}

TEST(OverlayConvert, HostileSamplesAreRejectedNamingTheField) {
  msg::CueOverlay good;
  ToMsg({"st-1", "session", 1, 1}, 0, Sample(), good);
  Header h;
  std::uint32_t active = 0;
  cues::CueOverlay out;
  struct Case {
    void (*spoil)(msg::CueOverlay&);
    const char* field;
  };
  const Case cases[] = {
      {[](msg::CueOverlay& m) {
         m.polylines()[0].p_W()[1] = std::numeric_limits<double>::quiet_NaN();
       },
       "polylines[].p_W"},
      {[](msg::CueOverlay& m) { m.polylines()[0].p_W().pop_back(); }, "polylines[].p_W"},
      {[](msg::CueOverlay& m) { m.polylines()[0].p_W().resize(3 * 65, 0.0); }, "polylines[].p_W"},
      {[](msg::CueOverlay& m) { m.polylines()[0].rgba()[0] = 2; }, "polylines[].rgba"},
      {[](msg::CueOverlay& m) { m.polylines()[1].role(9); }, "polylines[].role"},
      {[](msg::CueOverlay& m) { m.polylines()[0].width_m(-1); }, "polylines[].width_m"},
      {[](msg::CueOverlay& m) { m.labels()[0].p_W()[2] = std::numeric_limits<double>::infinity(); },
       "labels[].p_W"},
  };
  for (const Case& c : cases) {
    msg::CueOverlay m = good;
    c.spoil(m);
    std::string why;
    EXPECT_FALSE(FromMsg(m, h, active, out, &why)) << c.field;
    EXPECT_EQ(why.rfind(c.field, 0), 0u) << why;
  }
}

}  // namespace
}  // namespace microdex::net
