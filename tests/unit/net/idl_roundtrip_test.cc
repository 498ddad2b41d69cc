// The generated DDS types serialise to CDR and back without loss.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <gtest/gtest.h>

#include "station_info.h"
#include "station_infoPubSubTypes.h"

namespace microdex::msg {
namespace {

StationInfo MakeInfo() {
  StationInfo info;
  info.station_id("station-3");
  info.session_id("2026-11-21T10:00:00Z/3");
  info.step(123456789012ULL);
  info.stamp_ns(-42);
  info.trainee("Dr. Ünal");
  info.scene("assets/scenes/needle_tube.yaml");
  info.modules({"needle", "tremor"});
  info.build("0.1.0");
  info.haptic_rate_hz(1000.0);
  return info;
}

TEST(IdlRoundTrip, StationInfoSurvivesCdr) {
  StationInfoPubSubType type;
  StationInfo in = MakeInfo();
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&in)());
  ASSERT_TRUE(type.serialize(&in, &payload));
  EXPECT_GT(payload.length, 0u);

  StationInfo out;
  ASSERT_TRUE(type.deserialize(&payload, &out));
  EXPECT_EQ(out, in);
  EXPECT_EQ(out.modules().size(), 2u);
  EXPECT_EQ(out.modules()[1], "tremor");
  EXPECT_EQ(out.step(), 123456789012ULL);
}

TEST(IdlRoundTrip, KeyIsTheStationId) {
  StationInfoPubSubType type;
  EXPECT_TRUE(type.m_isGetKeyDefined);
  StationInfo a = MakeInfo();
  StationInfo b = MakeInfo();
  b.step(7);  // same station, other sample
  eprosima::fastrtps::rtps::InstanceHandle_t ha, hb;
  ASSERT_TRUE(type.getKey(&a, &ha));
  ASSERT_TRUE(type.getKey(&b, &hb));
  EXPECT_EQ(ha, hb);
  b.station_id("station-4");
  ASSERT_TRUE(type.getKey(&b, &hb));
  EXPECT_NE(ha, hb);
}

TEST(IdlRoundTrip, TruncatedPayloadIsRejected) {
  StationInfoPubSubType type;
  StationInfo in = MakeInfo();
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&in)());
  ASSERT_TRUE(type.serialize(&in, &payload));
  payload.length = payload.length / 2;  // a hostile or corrupt sample
  StationInfo out;
  EXPECT_FALSE(type.deserialize(&payload, &out));
}

}  // namespace
}  // namespace microdex::msg
