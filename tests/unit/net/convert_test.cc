// Plain structs go to the DDS types and back unchanged; a received sample outside the IDL
// bounds or with non-finite numbers is refused with a reason naming the field.
#include "common/net/convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace microdex::net {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

Header MakeHeader() { return {"station-2", "session-9", 4242, 1700000000123456789LL}; }

void ExpectHeader(const Header& a, const Header& b) {
  EXPECT_EQ(a.station_id, b.station_id);
  EXPECT_EQ(a.session_id, b.session_id);
  EXPECT_EQ(a.step, b.step);
  EXPECT_EQ(a.stamp_ns, b.stamp_ns);
}

TEST(NetConvert, StationInfoRoundTrip) {
  StationInfo in{
      MakeHeader(), "trainee A", "needle_tube.yaml", {"needle", "tremor"}, "0.1.0", 1000.0, 60.0,
      0.3,          "sim"};
  msg::StationInfo m;
  ToMsg(in, m);
  StationInfo out;
  ASSERT_TRUE(FromMsg(m, out));
  ExpectHeader(out.header, in.header);
  EXPECT_EQ(out.modules, in.modules);
  EXPECT_EQ(out.trainee, in.trainee);
  EXPECT_EQ(out.skill, 0.3);
}

TEST(NetConvert, NeedleStateRoundTripAndFlag) {
  NeedleState in;
  in.header = MakeHeader();
  in.p_WN = {1e-3, 2e-3, -3e-3};
  in.q_WN = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  in.clearance_m = -2e-5;
  in.contact = true;
  in.s_rad = 1.1;
  in.p_WD = {1, 2, 3};
  in.p_WB = {4, 5, 6};
  msg::NeedleState m;
  ToMsg(in, m);
  EXPECT_EQ(m.contact(), 1);
  NeedleState out;
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_TRUE(out.contact);
  EXPECT_EQ(out.p_WN, in.p_WN);
  EXPECT_EQ(out.q_WN.coeffs(), in.q_WN.coeffs());
  EXPECT_EQ(out.clearance_m, in.clearance_m);

  m.contact(7);  // neither 0 nor 1
  std::string why;
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("contact"), std::string::npos) << why;
}

TEST(NetConvert, NeedleStateWithoutClearanceMayCarryNan) {
  NeedleState in;
  in.header = MakeHeader();
  in.status = ClearanceStatus::kEmptyRange;
  in.clearance_m = kNan;
  msg::NeedleState m;
  ToMsg(in, m);
  NeedleState out;
  EXPECT_TRUE(FromMsg(m, out));
  EXPECT_EQ(out.status, ClearanceStatus::kEmptyRange);
  m.status(msg::CLEARANCE_OK);  // the same NaN claimed valid
  std::string why;
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("clearance_m"), std::string::npos) << why;
  m.status(static_cast<msg::NeedleClearanceStatus>(3));  // no such status
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("status"), std::string::npos) << why;
}

// Statuses cross by name: every plain enumerator arrives as itself.
TEST(NetConvert, StatusesCrossByName) {
  for (const ClearanceStatus s :
       {ClearanceStatus::kOk, ClearanceStatus::kEmptyRange, ClearanceStatus::kInvalidInput}) {
    NeedleState in;
    in.header = MakeHeader();
    in.status = s;
    in.clearance_m = s == ClearanceStatus::kOk ? 1e-4 : kNan;
    msg::NeedleState m;
    ToMsg(in, m);
    NeedleState out;
    ASSERT_TRUE(FromMsg(m, out));
    EXPECT_EQ(out.status, s);
  }
  EXPECT_EQ(static_cast<int>(msg::CLEARANCE_EMPTY_RANGE), 1);
  int tissue_statuses = 0;
  for (int k = 0; k <= static_cast<int>(TissueStepStatus::kNonFinite); ++k) {
    TissueState in;
    in.header = MakeHeader();
    in.length_x_m = in.length_y_m = 0.02;
    in.status = static_cast<TissueStepStatus>(k);
    msg::TissueState m;
    ToMsg(in, m);
    TissueState out;
    ASSERT_TRUE(FromMsg(m, out));
    EXPECT_EQ(out.status, in.status);
    ++tissue_statuses;
  }
  EXPECT_EQ(tissue_statuses, 7);
}

TEST(NetConvert, DeviceInputRejectsNonFiniteAndNonUnit) {
  DeviceInput in;
  in.header = MakeHeader();
  in.p_WT = {1e-3, 0, 0};
  msg::DeviceInput m;
  ToMsg(in, m);
  DeviceInput out;
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_EQ(out.p_WT, in.p_WT);

  std::string why;
  m.p_WT({kNan, 0, 0});
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("p_WT"), std::string::npos) << why;
  m.p_WT({0, 0, 0});
  m.q_WT({2, 0, 0, 0});
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("q_WT"), std::string::npos) << why;
}

TEST(NetConvert, DeviceInputRejectsOutOfRangeAndBadStationId) {
  DeviceInput in;
  in.header = MakeHeader();
  msg::DeviceInput m;
  ToMsg(in, m);
  DeviceInput out;
  std::string why;
  m.p_WT({0, 11.0, 0});  // 11 m: beyond any scene
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("p_WT: outside"), std::string::npos) << why;
  m.p_WT({0, 9.0, 0});
  EXPECT_TRUE(FromMsg(m, out, &why)) << why;
  m.gripper(1.5);
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("gripper"), std::string::npos) << why;
  m.gripper(1.0);
  EXPECT_TRUE(FromMsg(m, out, &why)) << why;
  for (const char* bad : {"st 1", "st\n1", "st\x1b[2J", "st\xc3\xa9"}) {
    m.station_id(bad);
    EXPECT_FALSE(FromMsg(m, out, &why)) << bad;
    EXPECT_NE(why.find("station_id"), std::string::npos) << why;
  }
  m.station_id("st-1_a.b");
  EXPECT_TRUE(FromMsg(m, out, &why)) << why;
}

TEST(NetConvert, ThreadStateBoundIsEnforcedOnReceipt) {
  ThreadState in;
  in.header = MakeHeader();
  in.nodes.assign(kMaxThreadNodes, Eigen::Vector3d(1e-3, 2e-3, 3e-3));
  in.knot = "square";
  in.max_strain = 0.012;
  in.grasped_node = static_cast<std::int32_t>(kMaxThreadNodes) - 1;
  in.f_T_W = Eigen::Vector3d(0.1, -0.2, 0.3);
  msg::ThreadState m;
  ToMsg(in, m);
  ThreadState out;
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_EQ(out.nodes.size(), kMaxThreadNodes);
  EXPECT_EQ(out.knot, "square");
  EXPECT_EQ(out.max_strain, in.max_strain);
  EXPECT_EQ(out.grasped_node, in.grasped_node);
  EXPECT_EQ(out.f_T_W, in.f_T_W);
  std::string why;
  m.grasped_node(static_cast<std::int32_t>(kMaxThreadNodes));  // not a node
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("grasped_node"), std::string::npos) << why;
  m.grasped_node(-1);
  m.f_T_W({0, std::nan(""), 0});
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("f_T_W"), std::string::npos) << why;
  m.f_T_W({0, 0, 0});
  m.nodes().push_back(m.nodes().back());  // one over the bound
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("nodes"), std::string::npos) << why;
}

TEST(NetConvert, TissueStateRoundTripAndBound) {
  TissueState in;
  in.header = MakeHeader();
  in.p_WS = Eigen::Vector3d(-0.01, -0.01, 0);
  in.q_WS = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  in.length_x_m = 0.02;
  in.length_y_m = 0.03;
  in.nodes_x = 3;
  in.nodes_y = 2;
  in.mesh_revision = 3;
  in.unknowns = 900;
  in.max_displacement_m = 2e-6;
  in.status = TissueStepStatus::kOk;
  in.displacement_m = {1e-6f, -2e-6f, 0.0f, 0.5e-6f, 0.0f, 0.0f};
  msg::TissueState m;
  ToMsg(in, m);
  TissueState out;
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_EQ(out.displacement_m, in.displacement_m);
  EXPECT_EQ(out.p_WS, in.p_WS);
  EXPECT_TRUE(out.q_WS.isApprox(in.q_WS, 0));
  EXPECT_EQ(out.length_y_m, in.length_y_m);
  EXPECT_EQ(out.nodes_x, 3u);
  EXPECT_EQ(out.nodes_y, 2u);
  EXPECT_EQ(out.mesh_revision, 3u);
  EXPECT_EQ(out.unknowns, 900u);
  std::string why;
  m.nodes_x(4);  // grid size no longer matches the values
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("nodes_x"), std::string::npos) << why;
  m.nodes_x(3);
  m.status(static_cast<msg::TissueStepStatus>(7));  // no such status
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("status"), std::string::npos) << why;
  m.status(msg::TISSUE_OK);
  m.length_x_m(0);
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("length_x_m"), std::string::npos) << why;
  m.length_x_m(0.02);
  m.displacement_m().resize(kMaxTissueNodes + 1);
  m.nodes_x(static_cast<std::uint32_t>(kMaxTissueNodes + 1));
  m.nodes_y(1);
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("displacement_m"), std::string::npos) << why;
}

TEST(NetConvert, CueCommandKindsAndRejection) {
  for (std::uint32_t k = 0; k < cues::kCueKindCount; ++k) {
    CueCommand in;
    in.header = MakeHeader();
    in.header.station_id = kAllStations;
    in.cue_id = 17 + k;
    in.kind = static_cast<cues::CueKind>(k);
    in.param = 120.5;
    in.issuer = "instructor";
    msg::CueCommand m;
    ToMsg(in, m);
    CueCommand out;
    ASSERT_TRUE(FromMsg(m, out));
    EXPECT_EQ(out.kind, in.kind);
    EXPECT_EQ(out.cue_id, in.cue_id);
    EXPECT_EQ(out.header.station_id, "all");
    cues::CueKind parsed;
    ASSERT_TRUE(cues::ParseCueKind(cues::CueKindName(in.kind), &parsed));
    EXPECT_EQ(parsed, in.kind);
  }
  msg::CueCommand m;
  m.station_id("station-1");
  m.kind(static_cast<msg::CueKind>(cues::kCueKindCount + 3));
  CueCommand out;
  std::string why;
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("kind"), std::string::npos) << why;
  cues::CueKind parsed;
  EXPECT_FALSE(cues::ParseCueKind("vortex", &parsed));
}

TEST(NetConvert, ActiveCuesCrossByKindName) {
  for (std::uint32_t mask = 0; mask < (1u << cues::kCueKindCount); ++mask) {
    ToolState in;
    in.header = MakeHeader();
    in.q_WT = Eigen::Quaterniond::Identity();
    in.active_cues = mask;
    msg::ToolState m;
    ToMsg(in, m);
    // Each set bit is the IDL's value of the kind of the same name.
    for (std::uint32_t k = 0; k < cues::kCueKindCount; ++k) {
      const auto kind = static_cast<cues::CueKind>(k);
      CueCommand c;
      c.header = MakeHeader();
      c.kind = kind;
      msg::CueCommand cm;
      ToMsg(c, cm);
      EXPECT_EQ((m.active_cues() >> static_cast<std::uint32_t>(cm.kind())) & 1u, (mask >> k) & 1u)
          << cues::CueKindName(kind);
    }
    ToolState out;
    ASSERT_TRUE(FromMsg(m, out));
    EXPECT_EQ(out.active_cues, mask);
  }
  msg::ToolState m;
  m.station_id("station-1");
  m.q_WT({1, 0, 0, 0});
  m.active_cues(1u << 20);  // no kind has that value
  ToolState out;
  std::string why;
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("active_cues"), std::string::npos) << why;
}

TEST(NetConvert, PlacedStitchesCrossAndBadOnesAreRefused) {
  ToolState in;
  in.header = MakeHeader();
  in.stitch_count = 2;
  in.stitch_azimuth_rad = {0.25F, 6.2F};
  in.stitch_bite_m = {3e-4F, -1e-4F};
  msg::ToolState m;
  ToMsg(in, m);
  ASSERT_EQ(m.stitch_azimuth_rad().size(), 2u);
  ToolState out;
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_EQ(out.stitch_count, 2);
  EXPECT_EQ(out.stitch_azimuth_rad[1], 6.2F);
  EXPECT_EQ(out.stitch_bite_m[1], -1e-4F);
  // Another scene: none.
  ToMsg(ToolState{.header = MakeHeader()}, m);
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_EQ(out.stitch_count, 0);
  // Refused, naming the field: unequal lengths, an azimuth outside [0, 2π), a NaN bite.
  const auto refused = [&](std::vector<float> az, std::vector<float> bite, const char* field) {
    ToMsg(in, m);
    m.stitch_azimuth_rad(az);
    m.stitch_bite_m(bite);
    std::string why;
    EXPECT_FALSE(FromMsg(m, out, &why)) << field;
    EXPECT_NE(why.find(field), std::string::npos) << why;
  };
  refused({0.1F, 0.2F}, {1e-4F}, "stitch_azimuth_rad");
  refused({-0.1F}, {1e-4F}, "stitch_azimuth_rad");
  refused({7.0F}, {1e-4F}, "stitch_azimuth_rad");
  refused({0.1F}, {std::numeric_limits<float>::quiet_NaN()}, "stitch_bite_m");
}

TEST(NetConvert, SecondToolCrossesAndIsCheckedOnlyWhenPresent) {
  ToolState in;
  in.header = MakeHeader();
  in.has_second_tool = true;
  in.p_WT2 = {1e-3, 2e-3, -3e-3};
  in.q_WT2 = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()));
  in.f_T2_W = {0.1, 0, -0.2};
  msg::ToolState m;
  ToMsg(in, m);
  ToolState out;
  ASSERT_TRUE(FromMsg(m, out));
  EXPECT_TRUE(out.has_second_tool);
  EXPECT_EQ(out.p_WT2, in.p_WT2);
  EXPECT_TRUE(out.q_WT2.isApprox(in.q_WT2, 1e-15));
  EXPECT_EQ(out.f_T2_W, in.f_T2_W);
  // A hostile second pose is refused, naming the field.
  m.p_WT2({0, std::nan(""), 0});
  std::string why;
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("p_WT2"), std::string::npos) << why;
  // Without a second tool its fields are ignored (a one-handed station sends zeros).
  m.has_second_tool(7);
  EXPECT_FALSE(FromMsg(m, out, &why));
  EXPECT_NE(why.find("has_second_tool"), std::string::npos) << why;
  m.has_second_tool(0);
  m.q_WT2({0, 0, 0, 0});
  ASSERT_TRUE(FromMsg(m, out, &why)) << why;
  EXPECT_FALSE(out.has_second_tool);
  EXPECT_EQ(out.q_WT2.w(), 1.0);
}

TEST(NetConvert, EmptyStationIdIsRejectedOverlongIsCut) {
  msg::Score m;
  Score out;
  std::string why;
  EXPECT_FALSE(FromMsg(m, out, &why));  // empty station_id
  EXPECT_NE(why.find("station_id"), std::string::npos) << why;
  // The generated bounded string keeps at most 64 characters: a longer id arrives cut.
  m.station_id(std::string(80, 'x'));
  EXPECT_TRUE(FromMsg(m, out, &why)) << why;
  EXPECT_EQ(out.header.station_id, std::string(64, 'x'));
}

TEST(NetConvert, TelemetryAndScoreRoundTrip) {
  Telemetry t;
  t.header = MakeHeader();
  t.window_s = 0.1;
  t.ticks = 100;
  t.period_mean_s = 1e-3;
  t.period_p99_s = 1.02e-3;
  t.period_max_s = 3e-3;
  t.overruns = 1;
  t.realtime = true;
  t.cues_invalid = 3;
  t.device_samples_invalid = 41;
  t.modules.push_back({"needle", 1e-6, 4e-6, 2e-9, "sp_vs_exact_m", 0});
  msg::Telemetry tm;
  ToMsg(t, tm);
  Telemetry t2;
  ASSERT_TRUE(FromMsg(tm, t2));
  EXPECT_EQ(t2.cues_invalid, 3u);
  EXPECT_EQ(t2.device_samples_invalid, 41u);
  ASSERT_EQ(t2.modules.size(), 1u);
  EXPECT_EQ(t2.modules[0].name, "needle");
  EXPECT_EQ(t2.modules[0].error_estimate, 2e-9);
  EXPECT_TRUE(t2.realtime);

  Score s;
  s.header = MakeHeader();
  s.is_final = true;
  s.score = 88;
  s.contacts = 3;
  msg::Score sm;
  ToMsg(s, sm);
  Score s2;
  ASSERT_TRUE(FromMsg(sm, s2));
  EXPECT_TRUE(s2.is_final);
  EXPECT_EQ(s2.contacts, 3u);
  EXPECT_EQ(s2.score, 88);
}

}  // namespace
}  // namespace microdex::net
