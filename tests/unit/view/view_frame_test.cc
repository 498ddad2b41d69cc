// The frame layout (view_frame.h; common/view/src/frame.ts reads it): header, scalars at their
// indices, thread nodes and the tissue field after them, sections cut at their bounds; the
// scene JSON's shapes.
#include "common/view/view_frame.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "common/base/json_text.h"
#include "common/scene/scene.h"
#include "common/view/scene_view.h"

namespace microdex::view {
namespace {

std::uint32_t U32(const FrameBytes& f, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, f.bytes.data() + at, 4);
  return v;
}
std::uint16_t U16(const FrameBytes& f, std::size_t at) {
  std::uint16_t v = 0;
  std::memcpy(&v, f.bytes.data() + at, 2);
  return v;
}
double Scalar(const FrameBytes& f, int i) {
  double v = 0;
  std::memcpy(&v, f.bytes.data() + kFrameHeaderBytes + 8 * i, 8);
  return v;
}
float F32(const FrameBytes& f, std::size_t at) {
  float v = 0;
  std::memcpy(&v, f.bytes.data() + at, 4);
  return v;
}

TEST(ViewFrame, ToolOnlyFrame) {
  net::ToolState tool;
  tool.header.step = 1234;
  tool.header.stamp_ns = 1'700'000'000'123'456'789;
  tool.p_WT = {1e-3, -2e-3, 3e-3};
  tool.q_WT = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  tool.active_cues = 1u << 2;
  FrameSource src;
  src.slot = 7;
  src.tool = &tool;
  auto f = std::make_unique<FrameBytes>();
  EncodeFrame(src, *f);
  EXPECT_EQ(U32(*f, 0), kFrameMagic);
  EXPECT_EQ(std::memcmp(f->bytes.data(), "MDXF", 4), 0);
  EXPECT_EQ(U16(*f, 4), kFrameVersion);
  EXPECT_EQ(U16(*f, 6), 0);  // no section
  EXPECT_EQ(U32(*f, 8), 7u);
  EXPECT_EQ(U32(*f, 12), 0u);
  EXPECT_EQ(f->size, kFrameHeaderBytes + 8 * kScalarCount);
  EXPECT_EQ(Scalar(*f, kStep), 1234);
  EXPECT_NEAR(Scalar(*f, kStampMs), 1'700'000'000'123.456789, 1e-3);
  EXPECT_EQ(Scalar(*f, kToolP + 1), -2e-3);
  EXPECT_EQ(Scalar(*f, kToolQ), tool.q_WT.w());
  EXPECT_EQ(Scalar(*f, kToolQ + 3), tool.q_WT.z());
  EXPECT_EQ(Scalar(*f, kActiveCues), 4);
  EXPECT_EQ(Scalar(*f, kTool2Q), 1) << "no second tool: its rotation is the identity";
}

TEST(ViewFrame, SecondToolOfABimanualScene) {
  net::ToolState tool;
  tool.has_second_tool = true;
  tool.p_WT2 = {-5e-3, 1e-3, 2e-3};
  tool.q_WT2 = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX()));
  tool.f_T2_W = {0.01, -0.02, 0.03};
  FrameSource src;
  src.tool = &tool;
  auto f = std::make_unique<FrameBytes>();
  EncodeFrame(src, *f);
  EXPECT_EQ(U16(*f, 6), kHasSecondTool);
  EXPECT_EQ(Scalar(*f, kTool2P), -5e-3);
  EXPECT_EQ(Scalar(*f, kTool2P + 2), 2e-3);
  EXPECT_EQ(Scalar(*f, kTool2Q), tool.q_WT2.w());
  EXPECT_EQ(Scalar(*f, kTool2Q + 1), tool.q_WT2.x());
  EXPECT_EQ(Scalar(*f, kTool2Force + 1), -0.02);
  EXPECT_LE(kTool2Force + 3, kScalarCount);
}

TEST(ViewFrame, PlacedStitchesFollowTheToolState) {
  net::ToolState tool;
  tool.stitch_count = 3;
  tool.stitch_azimuth_rad = {0.5F, 2.0F, 6.0F};
  tool.stitch_bite_m = {3e-4F, 2.5e-4F, 3.5e-4F};
  FrameSource src;
  src.tool = &tool;
  auto f = std::make_unique<FrameBytes>();
  EncodeFrame(src, *f);
  EXPECT_EQ(Scalar(*f, kStitchCount), 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(Scalar(*f, kStitchAzimuth + i), tool.stitch_azimuth_rad[static_cast<std::size_t>(i)]);
    EXPECT_EQ(Scalar(*f, kStitchBite + i), tool.stitch_bite_m[static_cast<std::size_t>(i)]);
  }
  EXPECT_EQ(Scalar(*f, kStitchAzimuth + 3), 0) << "slots beyond the count stay zero";
  tool.stitch_count = 40;  // beyond the bound: cut to it
  EncodeFrame(src, *f);
  EXPECT_EQ(Scalar(*f, kStitchCount), 16);
  EXPECT_EQ(kStitchBite + 16, kScalarCount);
}

TEST(ViewFrame, ThreadAndTissueFollowTheScalars) {
  net::ToolState tool;
  net::ThreadState thread;
  thread.nodes = {{0, 0, 0}, {1e-3, 2e-3, 3e-3}};
  thread.max_strain = 0.02;
  net::TissueState tissue;
  tissue.nodes_x = 3;
  tissue.nodes_y = 2;
  tissue.displacement_m = {0, -1e-4f, 0, 0, -2e-4f, 0};
  tissue.length_x_m = 0.02;
  net::Score score;
  score.score = 87.5;
  FrameSource src;
  src.tool = &tool;
  src.thread = &thread;
  src.tissue = &tissue;
  src.score = &score;
  auto f = std::make_unique<FrameBytes>();
  EncodeFrame(src, *f);
  EXPECT_EQ(U16(*f, 6), kHasThread | kHasTissue | kHasScore);
  EXPECT_EQ(U32(*f, 12), 2u);
  const std::size_t nodes_at = kFrameHeaderBytes + 8 * kScalarCount;
  EXPECT_FLOAT_EQ(F32(*f, nodes_at + 4 * 4), 2e-3f);  // node 1, y
  const std::size_t field_at = nodes_at + 2 * 3 * 4;
  EXPECT_FLOAT_EQ(F32(*f, field_at + 4 * 4), -2e-4f);
  EXPECT_EQ(f->size, field_at + 6 * 4);
  EXPECT_EQ(Scalar(*f, kTissueNodesX), 3);
  EXPECT_EQ(Scalar(*f, kTissueLx), 0.02);
  EXPECT_EQ(Scalar(*f, kScore), 87.5);
  EXPECT_EQ(Scalar(*f, kThreadStrain), 0.02);
}

TEST(ViewFrame, InconsistentTissueIsLeftOutAndLongSectionsCut) {
  net::ToolState tool;
  net::TissueState tissue;
  tissue.nodes_x = 4;
  tissue.nodes_y = 4;
  tissue.displacement_m.assign(10, 0.f);  // not 16
  net::ThreadState thread;
  thread.nodes.assign(kMaxFrameThreadNodes + 100, Eigen::Vector3d::Zero());
  FrameSource src;
  src.tool = &tool;
  src.tissue = &tissue;
  src.thread = &thread;
  auto f = std::make_unique<FrameBytes>();
  EncodeFrame(src, *f);
  EXPECT_EQ(U16(*f, 6), kHasThread);
  EXPECT_EQ(U32(*f, 12), kMaxFrameThreadNodes);
  EXPECT_EQ(f->size, kFrameHeaderBytes + 8 * kScalarCount + kMaxFrameThreadNodes * 12);
}

TEST(SceneView, JsonHasTheSceneShapes) {
  const scene::SceneModel s = scene::LoadScene("assets/scenes/loop_along_wire.yaml");
  const std::string j = SceneViewJson(s);
  EXPECT_NE(j.find("\"task\":\"loop_along_wire\""), std::string::npos);
  EXPECT_NE(j.find("\"wire\":{\"radius\":"), std::string::npos);
  EXPECT_NE(j.find("\"loop\":{\"radius\":"), std::string::npos);
  EXPECT_NE(j.find("\"magnification\":10"), std::string::npos);
  EXPECT_EQ(j.find("\"vessel\""), std::string::npos);  // no needle module
  EXPECT_EQ(j.find("nan"), std::string::npos);
  const scene::SceneModel n = scene::LoadScene("assets/scenes/needle_tube.yaml");
  const std::string jn = SceneViewJson(n);
  EXPECT_NE(jn.find("\"vessel\":{\"core_radius\":"), std::string::npos);
  EXPECT_NE(jn.find("\"needle\":{\"radius\":"), std::string::npos);
}

TEST(SceneView, TheQuizsKnotsAreDrawnWithTheirThreadsDiameter) {
  // Each item's tube is its tied knot's 25 um nylon at the knot's drawing scale (2.5 to 10),
  // not the parametric shapes' 15 um; "radius" the largest.
  const scene::SceneModel s = scene::LoadScene("assets/scenes/knot_topology.yaml");
  const std::string j = SceneViewJson(s);
  ASSERT_NE(j.find("\"radii\":["), std::string::npos);
  double largest = 0;
  for (std::size_t i = 0; i < s.knots->items.size(); ++i) {
    const double r = s.knots->ItemThreadDiameter(i) / 2;
    EXPECT_GE(r, 2.5 * 12.5e-6 - 1e-12) << i;
    EXPECT_LE(r, 10 * 12.5e-6 + 1e-12) << i;
    largest = std::max(largest, r);
  }
  EXPECT_NE(j.find("\"knots\":{\"radius\":" + JsonNumber(largest) + ","), std::string::npos)
      << j.substr(j.find("\"knots\""), 80);
}

TEST(SceneView, JsonNumberDigitsAndNonFinite) {
  EXPECT_EQ(JsonNumber(0.123456789012), "0.123456789");
  EXPECT_EQ(JsonNumber(0.123456789012, 6), "0.123457");
  EXPECT_EQ(JsonNumber(2.5e-5, 6), "2.5e-05");
  EXPECT_EQ(JsonNumber(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(JsonNumber(-std::numeric_limits<double>::infinity(), 6), "null");
}

TEST(SceneView, JsonQuoteEscapes) { EXPECT_EQ(JsonQuote("a\"b\\c\n"), "\"a\\\"b\\\\c\\u000a\""); }

}  // namespace
}  // namespace microdex::view
