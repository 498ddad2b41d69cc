// DDS Security (deploy/security/README.md): a course made by deploy/security/make-course;
// participants of this process with and without its identities. Without a valid certificate
// a participant matches and reads nothing; a station identity cannot publish cue commands nor
// write into another station's partition (nor a device driver drive another station); a tampered
// permissions file stops the app with a clear error; inside its own partition a station identity
// cannot speak for another station (the instructor refuses, counts and does not record such
// samples). Each check has a positive control with a valid identity, so it can fail.
#include "common/net/dds_security.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>

#include "common/net/convert.h"
#include "common/net/dds_context.h"
#include "common/net/topics.h"
#include "cue_commandPubSubTypes.h"
#include "device_inputPubSubTypes.h"
#include "instructor/instructor.h"
#include "station_infoPubSubTypes.h"
#include "task_eventPubSubTypes.h"
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

// "TOPIC STATION" → rows of the recording, and its metadata.
struct Recorded {
  std::map<std::string, int> rows;
  std::map<std::string, std::string> metadata;
};
Recorded ReadRecording(const std::string& file) {
  Recorded r;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    return r;
  }
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db,
                     "SELECT t.name || ' ' || m.station, count(*) FROM messages m JOIN topics t "
                     "ON t.id = m.topic_id GROUP BY 1",
                     -1, &st, nullptr);
  while (sqlite3_step(st) == SQLITE_ROW) {
    r.rows[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] = sqlite3_column_int(st, 1);
  }
  sqlite3_finalize(st);
  sqlite3_prepare_v2(db, "SELECT key, value FROM metadata", -1, &st, nullptr);
  while (sqlite3_step(st) == SQLITE_ROW) {
    r.metadata[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] =
        reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return r;
}

// Samples of station `id` that pass every check of net::FromMsg.
msg::StationInfo InfoMsg(const std::string& id, const std::string& trainee) {
  net::StationInfo p;
  p.header = {id, id + "-session", 0, 1};
  p.trainee = trainee;
  p.scene = "needle_tube.yaml";
  msg::StationInfo m;
  net::ToMsg(p, m);
  return m;
}
msg::DeviceInput InputMsg(const std::string& id, std::uint64_t step) {
  net::DeviceInput p;
  p.header = {id, id + "-session", step, 1};
  msg::DeviceInput m;
  net::ToMsg(p, m);
  return m;
}
msg::TaskEvent EventMsg(const std::string& id, std::uint64_t step) {
  net::TaskEvent p;
  p.header = {id, id + "-session", step, 1};
  p.kind = net::TaskEventKind::kContactBegin;
  msg::TaskEvent m;
  net::ToMsg(p, m);
  return m;
}

// A station identity writes, in its own partition, samples claiming to be another station
// (StationInfo, DeviceInput, TaskEvent, and a disposal of the other's StationInfo): the
// instructor mirrors none of them, records none and counts each by topic, while the same
// writers' samples of their own station (the control) are mirrored and recorded.
TEST_F(DdsSecurity, AStationIdentityCannotSpeakForAnotherStationInItsPartition) {
  const std::string file = *root_ + "/spoof.db";
  instructor::InstructorOptions io;
  io.dds = Options(Dir("c1", "instructor-i1"), "", "secure-instructor");
  io.issuer = "i1";
  io.record_file = file;
  auto console = std::make_unique<instructor::Instructor>(io);

  // The real s2 announces itself first.
  net::DdsContext s2(Options(Dir("c1", "station-s2"), "s2", "station-s2"));
  dds::DataWriter* s2_info = s2.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  msg::StationInfo real_s2 = InfoMsg("s2", "real s2");
  ASSERT_TRUE(s2_info->write(&real_s2));
  ASSERT_TRUE(testing::WaitUntil([&] { return console->Station("s2").has_value(); }, 15000ms))
      << "the instructor never saw station s2";

  // s1's identity: writers for its own samples (the control) and, beside them in the same
  // partition, writers for samples that claim to be s2 (a writer holds one instance).
  net::DdsContext s1(Options(Dir("c1", "station-s1"), "s1", "station-s1"));
  dds::DataWriter* info = s1.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  dds::DataWriter* input = s1.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceInputTopic);
  dds::DataWriter* events = s1.CreateWriter<msg::TaskEventPubSubType>(net::kTaskEventTopic);
  dds::DataWriter* fake_info = s1.CreateWriter<msg::StationInfoPubSubType>(net::kStationInfoTopic);
  dds::DataWriter* fake_input = s1.CreateWriter<msg::DeviceInputPubSubType>(net::kDeviceInputTopic);
  dds::DataWriter* fake_events = s1.CreateWriter<msg::TaskEventPubSubType>(net::kTaskEventTopic);
  // Wait for the instructor's readers (DeviceInput is volatile: samples written before the
  // match are not delivered).
  ASSERT_TRUE(testing::WaitUntil(
      [&] {
        for (dds::DataWriter* w : {input, events, fake_input, fake_events}) {
          dds::PublicationMatchedStatus st;
          w->get_publication_matched_status(st);
          if (st.current_count == 0) return false;
        }
        return true;
      },
      15000ms));
  constexpr int kSteps = 40;
  msg::StationInfo spoofed = InfoMsg("s2", "spoofed");
  ASSERT_TRUE(fake_info->write(&spoofed));
  for (int i = 1; i <= kSteps; ++i) {
    msg::DeviceInput fake = InputMsg("s2", i);
    ASSERT_TRUE(fake_input->write(&fake));
    if (i % 10 == 0) {
      msg::TaskEvent fake_event = EventMsg("s2", i);
      ASSERT_TRUE(fake_events->write(&fake_event));
    }
  }
  // StationInfo keeps one sample per instance: the disposal would replace the spoofed sample
  // if it came before the instructor took it.
  ASSERT_TRUE(testing::WaitUntil(
      [&] { return console->Rejected().by_topic.count("station_info") > 0; }, 15000ms))
      << "the spoofed StationInfo was not refused";
  ASSERT_EQ(fake_info->dispose(&spoofed, fake_info->register_instance(&spoofed)),
            ReturnCode_t::RETCODE_OK);
  // The control: s1's own samples.
  msg::StationInfo own = InfoMsg("s1", "s1 trainee");
  ASSERT_TRUE(info->write(&own));
  for (int i = 1; i <= kSteps; ++i) {
    msg::DeviceInput m = InputMsg("s1", i);
    ASSERT_TRUE(input->write(&m));
  }
  msg::TaskEvent own_event = EventMsg("s1", 1);
  ASSERT_TRUE(events->write(&own_event));

  const bool all_in = testing::WaitUntil(
      [&] {
        const auto v = console->Station("s1");
        return v && v->inputs_received == kSteps && !v->events.empty() &&
               console->Rejected().total >= kSteps + 4 + 2;
      },
      15000ms);
  const instructor::RejectedSamples rejected = console->Rejected();
  ASSERT_TRUE(all_in) << instructor::FormatRejected(rejected);
  const auto v1 = console->Station("s1");
  EXPECT_EQ(v1->info.trainee, "s1 trainee");
  const auto v2 = console->Station("s2");
  ASSERT_TRUE(v2.has_value());
  EXPECT_EQ(v2->info.trainee, "real s2");
  EXPECT_NE(v2->presence, instructor::Presence::kDeparted) << "the spoofed disposal was taken";
  EXPECT_EQ(v2->inputs_received, 0u);
  EXPECT_TRUE(v2->events.empty());
  EXPECT_EQ(console->Stations().size(), 2u);
  // The spoofed StationInfo and its disposal, the 40 inputs, the 4 events.
  EXPECT_EQ(rejected.by_topic.count("station_info") ? rejected.by_topic.at("station_info") : 0, 2u);
  EXPECT_EQ(rejected.by_topic.count("device_input") ? rejected.by_topic.at("device_input") : 0,
            static_cast<std::uint64_t>(kSteps));
  EXPECT_EQ(rejected.by_topic.count("task_event") ? rejected.by_topic.at("task_event") : 0, 4u);
  EXPECT_EQ(rejected.total, static_cast<std::uint64_t>(kSteps) + 6);
  EXPECT_NE(rejected.last_reason.find("from a writer in the partition of 's1'"), std::string::npos)
      << rejected.last_reason;

  console->FlushRecording();
  const Recorded rec = ReadRecording(file);
  EXPECT_EQ(
      rec.rows.count("microdex/station_info s2") ? rec.rows.at("microdex/station_info s2") : 0, 1)
      << "only the real s2's StationInfo";
  EXPECT_EQ(rec.rows.count("microdex/device_input s2"), 0u);
  EXPECT_EQ(rec.rows.count("microdex/task_event s2"), 0u);
  EXPECT_EQ(
      rec.rows.count("microdex/device_input s1") ? rec.rows.at("microdex/device_input s1") : 0,
      kSteps);
  EXPECT_EQ(rec.metadata.count("rejected_samples") ? rec.metadata.at("rejected_samples") : "",
            "device_input 40\nstation_info 2\ntask_event 4\n");
  EXPECT_NE(rec.metadata.count("rejected_latest") ? rec.metadata.at("rejected_latest") : "", "");
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
