// DDS Security (deploy/security/README.md): a course made by deploy/security/make-course;
// participants of this process with and without its identities. Without a valid certificate
// a participant matches and reads nothing; a station identity cannot publish cue commands nor
// write into another station's partition (nor a device driver drive another station); a tampered
// permissions file stops the app with a clear error. Each check has a positive control with a valid
// identity, so it can fail.
#include "common/net/dds_security.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>

#include "common/net/dds_context.h"
#include "common/net/topics.h"
#include "cue_commandPubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "station_infoPubSubTypes.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
namespace dds = eprosima::fastdds::dds;
namespace fs = std::filesystem;
using eprosima::fastrtps::types::ReturnCode_t;

constexpr int kDomain = 84;

// Two courses: "c1" (the course under test) and "intruder" made by its own CAs with the
// same station names, so its certificates are well-formed but not of c1.
class DdsSecurity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new std::string(::testing::TempDir() + "/dds_security_" + std::to_string(getpid()));
    fs::remove_all(*root_);
    const std::string script = testing::SourceDir() + "/deploy/security/make-course";
    for (const std::string course : {"c1", "intruder"}) {
      const std::string log = *root_ + "-" + course + ".log";
      std::string cmd = script;
      cmd += " " + *root_ + "/" + course;
      cmd +=
          " --course c1 --station s1 --station s2 --instructor i1 --device s1 > " + log + " 2>&1";
      ASSERT_EQ(std::system(cmd.c_str()), 0) << testing::ReadFile(log);
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
  }
  static std::string Dir(const std::string& course, const std::string& identity) {
    return *root_ + "/" + course + "/" + identity;
  }
  static net::DdsOptions Options(const std::string& security_dir, const std::string& station,
                                 const std::string& name) {
    net::DdsOptions o;
    o.profile_file = net::DefaultDdsProfileFile();
    o.domain_id = kDomain;
    o.participant_name = name;
    o.security_dir = security_dir;
    o.security_station = station;
    return o;
  }
  static std::string* root_;
};
std::string* DdsSecurity::root_ = nullptr;

// Station s1 (secure) writes its StationInfo (transient-local: late readers get it too).
std::unique_ptr<net::DdsContext> StartStation(const net::DdsOptions& o) {
  auto ctx = std::make_unique<net::DdsContext>(o);
  dds::DataWriter* w = ctx->CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  msg::StationInfo info;
  info.station_id("s1");
  info.trainee("secure trainee");
  EXPECT_TRUE(w->write(&info));
  return ctx;
}

// The StationInfo samples `reader` gets within `wait`, and whether it matched a writer.
struct ReadResult {
  int samples = 0;
  int matched = 0;
};
ReadResult ReadStationInfo(dds::DataReader* reader, std::chrono::milliseconds wait) {
  ReadResult r;
  testing::WaitUntil(
      [&] {
        msg::StationInfo m;
        dds::SampleInfo si;
        while (reader->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
          if (si.valid_data && m.station_id() == "s1") ++r.samples;
        }
        dds::SubscriptionMatchedStatus st;
        reader->get_subscription_matched_status(st);
        r.matched = st.total_count;
        return r.samples > 0;
      },
      wait);
  return r;
}

TEST_F(DdsSecurity, WithoutAValidCertificateNothingIsDiscoveredOrRead) {
  const auto station = StartStation(Options(Dir("c1", "station-s1"), "s1", "secure-station"));

  // A plain participant in the station's partition, and one with the intruder course's
  // identity (a certificate of another CA): neither matches the writer nor reads a sample.
  net::DdsOptions plain = Options("", "", "plain-eavesdropper");
  plain.partition = "c1/s1";
  net::DdsContext eavesdropper(plain);
  net::DdsContext intruder(Options(Dir("intruder", "instructor-i1"), "", "intruder"));
  dds::DataReader* plain_reader =
      eavesdropper.CreateReader<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  dds::DataReader* intruder_reader =
      intruder.CreateReader<msg::StationInfoPubSubType>(net::kStationInfoTopic);

  // Control: the course's instructor reads it.
  net::DdsContext instructor(Options(Dir("c1", "instructor-i1"), "", "secure-instructor"));
  EXPECT_EQ(instructor.partition(), "c1/*");
  dds::DataReader* good_reader =
      instructor.CreateReader<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  const ReadResult good = ReadStationInfo(good_reader, 15000ms);
  EXPECT_GE(good.samples, 1) << "the course's instructor did not read the secure station";
  EXPECT_GE(good.matched, 1);

  // The others had as long as the instructor, and 3 s more.
  const ReadResult p = ReadStationInfo(plain_reader, 3000ms);
  const ReadResult i = ReadStationInfo(intruder_reader, 1ms);
  EXPECT_EQ(p.samples, 0);
  EXPECT_EQ(p.matched, 0);
  EXPECT_EQ(i.samples, 0);
  EXPECT_EQ(i.matched, 0);
}

TEST_F(DdsSecurity, AStationIdentityCannotPublishCuesNorWriteForAnotherStation) {
  net::DdsContext s1(Options(Dir("c1", "station-s1"), "s1", "station-s1"));
  EXPECT_EQ(s1.partition(), "c1/s1");
  try {
    s1.CreateWriter<msg::CueCommandPubSubType>(net::kCueCommandTopic);
    ADD_FAILURE() << "a station identity created a cue command writer";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("grants no publishing of microdex/cue_command"),
              std::string::npos)
        << e.what();
  }
  // s1's own topics: allowed (control); in s2's partition: refused.
  EXPECT_NE(s1.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic), nullptr);
  net::DdsContext s1_as_s2(Options(Dir("c1", "station-s1"), "s2", "station-s1-as-s2"));
  EXPECT_EQ(s1_as_s2.partition(), "c1/s2");
  EXPECT_THROW(s1_as_s2.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic),
               std::runtime_error);
  EXPECT_THROW(s1_as_s2.CreateReader<msg::CueCommandPubSubType>(net::kCueCommandTopic),
               std::runtime_error);
  // A station cannot read another station's state either.
  EXPECT_THROW(s1.CreateReader<msg::StationInfoPubSubType>(net::kStationInfoTopic),
               std::runtime_error);

  // A device driver's identity drives its own station only.
  net::DdsContext device(Options(Dir("c1", "device-s1"), "s1", "device-s1"));
  EXPECT_NE(device.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceSampleTopic), nullptr);
  EXPECT_THROW(device.CreateWriter<msg::CueCommandPubSubType>(net::kCueCommandTopic),
               std::runtime_error);
  net::DdsContext device_as_s2(Options(Dir("c1", "device-s1"), "s2", "device-s1-as-s2"));
  EXPECT_THROW(device_as_s2.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceSampleTopic),
               std::runtime_error);

  // Control: the instructor identity publishes cues, and station s1 receives them.
  net::DdsContext instructor(Options(Dir("c1", "instructor-i1"), "", "instructor"));
  dds::DataWriter* cue_writer =
      instructor.CreateWriter<msg::CueCommandPubSubType>(net::kCueCommandTopic);
  ASSERT_NE(cue_writer, nullptr);
  dds::DataReader* cue_reader = s1.CreateReader<msg::CueCommandPubSubType>(net::kCueCommandTopic);
  msg::CueCommand cue;
  cue.station_id("s1");
  cue.cue_id(7);
  ASSERT_TRUE(cue_writer->write(&cue));
  std::uint64_t got = 0;
  EXPECT_TRUE(testing::WaitUntil(
      [&] {
        msg::CueCommand m;
        dds::SampleInfo si;
        while (cue_reader->take_next_sample(&m, &si) == ReturnCode_t::RETCODE_OK) {
          if (si.valid_data) got = m.cue_id();
        }
        return got == 7;
      },
      15000ms))
      << "station s1 did not receive the instructor's cue";
}

// A copy of `from` whose permissions.p7s grants partition c1/* instead of c1/s1 (the
// signature no longer matches the content).
std::string TamperedCopy(const std::string& from, const std::string& to) {
  fs::remove_all(to);
  fs::copy(from, to);
  std::string p7 = testing::ReadFile(from + "/permissions.p7s");
  const std::size_t at = p7.find("<partition>c1/s1</partition>");
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos) p7.replace(at, 28, "<partition>c1/*</partition>  ");
  std::ofstream(to + "/permissions.p7s", std::ios::trunc) << p7;
  return to;
}

TEST_F(DdsSecurity, ATamperedPermissionsFileStopsTheAppWithAClearError) {
  const std::string dir = TamperedCopy(Dir("c1", "station-s1"), Dir("c1", "tampered-s1"));
  try {
    net::LoadSecurityFiles(dir);
    ADD_FAILURE() << "a tampered permissions file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("permissions.p7s: its signature does not verify"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(net::LoadSecurityFiles(Dir("c1", "station-s1")));  // control

  const std::string log = ::testing::TempDir() + "/dds_security_tampered.log";
  std::remove(log.c_str());
  const pid_t pid = testing::Spawn(
      "microdex-station",
      {"--scene", testing::SourceDir() + "/assets/scenes/needle_tube.yaml", "--station-id", "s1",
       "--security", dir, "--domain", std::to_string(kDomain), "--duration", "2", "--no-realtime"},
      log);
  const std::optional<int> rc = testing::WaitExit(pid, 20000ms);
  if (!rc) testing::KillAll({pid});
  const std::string out = testing::ReadFile(log);
  EXPECT_EQ(rc.value_or(-1), 2) << out;
  EXPECT_NE(out.find("microdex-station: --security: "), std::string::npos) << out;
  EXPECT_NE(out.find("permissions.p7s: its signature does not verify"), std::string::npos) << out;
}

}  // namespace
}  // namespace microdex
