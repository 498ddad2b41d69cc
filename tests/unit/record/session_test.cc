// common/record: the writer and reader agree field for field; the topics are those of
// common/net with this build's IDL hashes; an existing file is never overwritten; the
// recorder writes everything pushed from several threads, and drops (and counts) what does
// not fit its queue; bad files are refused with the file named and the reason, and a topic
// whose type hash is unknown is skipped while the rest stays readable.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>

#include "common/net/topics.h"
#include "common/record/recorded_topics.h"
#include "common/record/recorder.h"
#include "common/record/session_reader.h"
#include "common/record/session_writer.h"

namespace microdex::record {
namespace {

std::string TmpDir() {
  std::string dir = "/tmp/microdex-record-unit-XXXXXX";
  return mkdtemp(dir.data()) ? dir : "/tmp";
}

RecordedMessage Message(int topic, const std::string& station, std::uint64_t step) {
  RecordedMessage m;
  m.topic = topic;
  m.station = station;
  m.session = station + "-session";
  m.receive_ns = 1'000'000'000 + static_cast<std::int64_t>(step) * 1000;
  m.source_ns = m.receive_ns - 7;
  m.sequence = static_cast<std::int64_t>(step) + 1;
  m.step = step;
  m.cdr = {0, 1, 0, 0, static_cast<std::uint8_t>(step), static_cast<std::uint8_t>(topic)};
  return m;
}

void Exec(const std::string& file, const char* sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
}

// The message of a RecordError from opening `file` ("" when it opens).
std::string OpenError(const std::string& file) {
  try {
    SessionReader r(file);
  } catch (const RecordError& e) {
    return e.what();
  }
  return "";
}

class SessionTest : public ::testing::Test {
 protected:
  std::string WriteSample(const std::string& name) {
    std::string file = dir_ + "/" + name;
    SessionWriter w(file, {{"issuer", "unit"}});
    std::vector<RecordedMessage> batch;
    for (std::uint64_t s = 0; s < 10; ++s) {
      batch.push_back(Message(static_cast<int>(TopicIndex::kDeviceInput), "a", s));
      batch.push_back(Message(static_cast<int>(TopicIndex::kTelemetry), "b", s));
    }
    w.Write(batch);
    return file;
  }
  std::string dir_ = TmpDir();
};

TEST_F(SessionTest, TopicsAreThoseOfTheDdsLayerWithThisBuildsIdlHashes) {
  const net::TopicSpec specs[] = {
      net::kStationInfoTopic, net::kDeviceInputTopic, net::kToolStateTopic,
      net::kNeedleStateTopic, net::kThreadStateTopic, net::kTissueStateTopic,
      net::kTelemetryTopic,   net::kCueCommandTopic,  net::kTaskEventTopic,
      net::kScoreTopic,       net::kCueOverlayTopic,  net::kDeviceForceTopic};
  ASSERT_EQ(KnownTopics().size(), std::size(specs));
  ASSERT_EQ(static_cast<int>(KnownTopics().size()), kTopicCount);
  for (std::size_t i = 0; i < std::size(specs); ++i) {
    EXPECT_EQ(KnownTopics()[i].name, specs[i].name);
    EXPECT_EQ(KnownTopics()[i].idl_hash.size(), 16u);
    EXPECT_EQ(FindTopic(specs[i].name), static_cast<int>(i));
  }
  EXPECT_NE(Topic(TopicIndex::kDeviceInput).idl_hash, Topic(TopicIndex::kTelemetry).idl_hash);
  EXPECT_EQ(FindTopic("microdex/nothing"), -1);
}

TEST_F(SessionTest, WhatIsWrittenIsReadBackFieldForField) {
  const std::string file = WriteSample("a.db");
  SessionReader r(file);
  EXPECT_EQ(r.schema_version(), kSchemaVersion);
  EXPECT_EQ(r.metadata().at("format"), kFormatName);
  EXPECT_EQ(r.metadata().at("issuer"), "unit");
  ASSERT_EQ(r.topics().size(), KnownTopics().size());
  for (const auto& t : r.topics()) EXPECT_GE(t.known, 0) << t.name;
  EXPECT_TRUE(r.problems().empty());
  std::vector<RecordedMessage> got;
  r.ForEach({}, [&](const MessageView& m) {
    RecordedMessage c;
    c.topic = m.topic;
    c.station = m.station;
    c.session = m.session;
    c.receive_ns = m.receive_ns;
    c.source_ns = m.source_ns;
    c.sequence = m.sequence;
    c.step = m.step;
    c.cdr.assign(m.cdr.begin(), m.cdr.end());
    got.push_back(c);
    return true;
  });
  ASSERT_EQ(got.size(), 20u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const RecordedMessage e =
        Message(static_cast<int>(i % 2 ? TopicIndex::kTelemetry : TopicIndex::kDeviceInput),
                i % 2 ? "b" : "a", i / 2);
    EXPECT_EQ(got[i].topic, e.topic);
    EXPECT_EQ(got[i].station, e.station);
    EXPECT_EQ(got[i].session, e.session);
    EXPECT_EQ(got[i].receive_ns, e.receive_ns);
    EXPECT_EQ(got[i].source_ns, e.source_ns);
    EXPECT_EQ(got[i].sequence, e.sequence);
    EXPECT_EQ(got[i].step, e.step);
    EXPECT_EQ(got[i].cdr, e.cdr);
  }
  // Filters: by topic and station, by time.
  std::size_t n = 0;
  r.ForEach({static_cast<int>(TopicIndex::kTelemetry), "b"}, [&](const MessageView& m) {
    EXPECT_EQ(m.station, "b");
    return ++n, true;
  });
  EXPECT_EQ(n, 10u);
  MessageFilter f;
  f.from_ns = 1'000'002'000;
  f.to_ns = 1'000'004'000;
  n = 0;
  r.ForEach(f, [&](const MessageView&) { return ++n, true; });
  EXPECT_EQ(n, 6u);  // steps 2, 3, 4 of both topics
  EXPECT_EQ(r.Stations(), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(r.TimeRange(),
            std::make_pair(std::int64_t{1'000'000'000}, std::int64_t{1'000'009'000}));
}

TEST_F(SessionTest, AnExistingFileIsNeverOverwritten) {
  const std::string file = WriteSample("a.db");
  try {
    SessionWriter w(file, {});
    FAIL() << "overwrote " << file;
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), file + ": already exists (a recording is never overwritten)");
  }
}

TEST_F(SessionTest, TheRecorderWritesEverythingPushedFromSeveralThreads) {
  const std::string file = dir_ + "/threads.db";
  constexpr int kThreads = 3, kPerThread = 20000;
  {
    Recorder rec(file, {});
    std::vector<std::thread> producers;
    producers.reserve(kThreads);
    for (int t = 0; t < kThreads; ++t) {
      producers.emplace_back([&rec, t] {
        for (int i = 0; i < kPerThread; ++i) {
          rec.Push(Message(static_cast<int>(TopicIndex::kDeviceInput),
                           std::string(1, 's').append(std::to_string(t)),
                           static_cast<std::uint64_t>(i)));
        }
      });
    }
    for (auto& p : producers) p.join();
    rec.Flush();
    const RecorderStats s = rec.stats();
    EXPECT_EQ(s.pushed, std::uint64_t{kThreads * kPerThread});
    EXPECT_EQ(s.dropped, 0u);
    EXPECT_EQ(s.written, std::uint64_t{kThreads * kPerThread});
    EXPECT_TRUE(s.error.empty()) << s.error;
  }
  SessionReader r(file);
  std::vector<std::uint64_t> next(kThreads, 0);
  std::size_t n = 0;
  bool in_order = true;
  r.ForEach({}, [&](const MessageView& m) {
    const int t = m.station[1] - '0';
    in_order = in_order && m.step == next[static_cast<std::size_t>(t)]++;
    return ++n, true;
  });
  EXPECT_EQ(n, std::size_t{kThreads * kPerThread});
  EXPECT_TRUE(in_order);  // each producer's messages in the order it pushed them
}

TEST_F(SessionTest, AFullQueueDropsAndCountsWithoutBlocking) {
  RecorderConfig c;
  c.queue_capacity = 5;
  c.commit_period = std::chrono::hours(1);  // the thread sleeps: nothing leaves the queue
  c.batch_wake = 1000;
  Recorder rec(dir_ + "/full.db", {}, c);
  int accepted = 0;
  for (int i = 0; i < 12; ++i) {
    accepted += rec.Push(Message(1, "a", static_cast<std::uint64_t>(i))) ? 1 : 0;
  }
  EXPECT_EQ(accepted, 5);
  const RecorderStats s = rec.stats();
  EXPECT_EQ(s.pushed, 12u);
  EXPECT_EQ(s.dropped, 7u);
  rec.Flush();
  EXPECT_EQ(rec.stats().written, 5u);
}

TEST_F(SessionTest, BadFilesAreRefusedNamingTheFileAndTheReason) {
  EXPECT_EQ(OpenError(dir_ + "/missing.db"), dir_ + "/missing.db: no such file");
  EXPECT_EQ(OpenError(dir_), dir_ + ": not a regular file");
  const std::string text = dir_ + "/notes.txt";
  std::ofstream(text) << "this is not a database, just some text long enough to have a header "
                         "that SQLite reads and rejects\n";
  EXPECT_EQ(OpenError(text), text + ": not an SQLite database");
  const std::string other = dir_ + "/other.db";
  Exec(other, "CREATE TABLE t(x)");
  EXPECT_EQ(OpenError(other).rfind(other + ": not a microdex recording (", 0), 0u)
      << OpenError(other);
  const std::string future = WriteSample("future.db");
  Exec(future, "UPDATE metadata SET value = '2' WHERE key = 'schema_version'");
  EXPECT_EQ(OpenError(future), future +
                                   ": schema version 2 is newer than this build reads (1): "
                                   "use a newer microdex-replay");
  const std::string wrong = WriteSample("wrong.db");
  Exec(wrong, "UPDATE metadata SET value = 'x1' WHERE key = 'schema_version'");
  EXPECT_EQ(OpenError(wrong), wrong + ": metadata schema_version: 'x1'");
  const std::string empty = dir_ + "/empty.db";
  std::ofstream(empty).flush();
  EXPECT_EQ(OpenError(empty).rfind(empty + ": not a microdex recording (", 0), 0u)
      << OpenError(empty);
}

TEST_F(SessionTest, ATopicWithAnUnknownTypeHashIsSkippedAndTheRestReads) {
  const std::string file = WriteSample("hash.db");
  Exec(file,
       "UPDATE topics SET idl_hash = '0123456789abcdef' WHERE name = 'microdex/device_input'");
  SessionReader r(file);
  ASSERT_EQ(r.problems().size(), 1u);
  EXPECT_EQ(r.problems()[0],
            file +
                ": topic 'microdex/device_input': unknown type hash 0123456789abcdef of "
                "microdex::msg::DeviceInput (this build: " +
                Topic(TopicIndex::kDeviceInput).idl_hash +
                "; recorded by another version, skipped)");
  std::size_t inputs = 0, telemetry = 0;
  r.ForEach({}, [&](const MessageView& m) {
    inputs += m.topic == static_cast<int>(TopicIndex::kDeviceInput);
    telemetry += m.topic == static_cast<int>(TopicIndex::kTelemetry);
    return true;
  });
  EXPECT_EQ(inputs, 0u);
  EXPECT_EQ(telemetry, 10u);
}

TEST_F(SessionTest, ATruncatedFileFailsCleanlyOrReadsItsReadablePart) {
  // A recording large enough to span many pages, cut at several places.
  const std::string file = dir_ + "/big.db";
  {
    SessionWriter w(file, {});
    std::vector<RecordedMessage> batch;
    for (std::uint64_t s = 0; s < 3000; ++s) {
      batch.push_back(Message(static_cast<int>(TopicIndex::kDeviceInput), "a", s));
      batch.back().cdr.resize(200, 7);
    }
    w.Write(batch);
  }
  std::ifstream in(file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 100'000u);
  for (const double keep : {0.001, 0.02, 0.3, 0.6, 0.95}) {
    const std::string cut = dir_ + "/cut.db";
    std::ofstream(cut, std::ios::binary | std::ios::trunc)
        << bytes.substr(0, static_cast<std::size_t>(keep * static_cast<double>(bytes.size())));
    try {
      SessionReader r(cut);
      std::size_t n = 0;
      r.ForEach({}, [&](const MessageView&) { return ++n, true; });
      // Whatever was readable came out; a short read is reported, naming the file.
      EXPECT_LE(n, 3000u);
      if (n < 3000) {
        ASSERT_FALSE(r.problems().empty()) << keep;
        EXPECT_EQ(r.problems()[0].rfind(cut + ": ", 0), 0u) << r.problems()[0];
      }
    } catch (const RecordError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(cut + ": ", 0), 0u) << e.what();
    }
  }
}

// The WAL is copied into the file by the checkpoint thread, not inside the commits: the writer's
// own connection never checkpoints (its WAL grows with what is written), the recorder's WAL
// stays a fraction of it, and everything written reads back.
TEST_F(SessionTest, TheCheckpointThreadKeepsTheWalShortAndLosesNothing) {
  auto wal_bytes = [](const std::string& db) {
    struct stat st {};
    return ::stat((db + "-wal").c_str(), &st) == 0 ? static_cast<long long>(st.st_size) : 0LL;
  };
  constexpr int kBatches = 40, kPerBatch = 500, kBytes = 1000;  // 20 MB of samples
  auto fill = [&](auto&& write) {
    for (int b = 0; b < kBatches; ++b) {
      std::vector<RecordedMessage> batch;
      for (int i = 0; i < kPerBatch; ++i) {
        RecordedMessage m = Message(static_cast<int>(TopicIndex::kDeviceInput), "a",
                                    static_cast<std::uint64_t>(b * kPerBatch + i));
        m.cdr.assign(kBytes, static_cast<std::uint8_t>(i));
        batch.push_back(std::move(m));
      }
      write(std::move(batch));
    }
  };
  constexpr long long kWritten = 1LL * kBatches * kPerBatch * kBytes;
  const std::string plain = dir_ + "/plain.db";
  {
    SessionWriter w(plain, {});
    fill([&](std::vector<RecordedMessage> batch) { w.Write(batch); });
    EXPECT_GT(wal_bytes(plain), kWritten) << "the writer checkpointed by itself";
  }
  const std::string file = dir_ + "/checkpointed.db";
  RecorderConfig config;
  config.checkpoint_period = std::chrono::milliseconds(5);
  long long wal_max = 0;
  {
    Recorder rec(file, {}, config);
    fill([&](std::vector<RecordedMessage> batch) {
      for (RecordedMessage& m : batch) ASSERT_TRUE(rec.Push(std::move(m)));
      rec.Flush();
      // Until a checkpoint after the commit has copied this batch (bounded: 2 s), however busy
      // the machine: the WAL's size then depends on the mechanism, not on the scheduler.
      const std::uint64_t before = rec.stats().checkpoints;
      for (int k = 0; k < 400 && rec.stats().checkpoints == before; ++k) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      wal_max = std::max(wal_max, wal_bytes(file));
    });
    const RecorderStats s = rec.stats();
    EXPECT_GT(s.checkpoints, 0u);
    EXPECT_TRUE(s.checkpoint_error.empty()) << s.checkpoint_error;
    EXPECT_EQ(s.written, std::uint64_t{kBatches * kPerBatch});
  }
  EXPECT_LT(wal_max, kWritten / 4);
  SessionReader r(file);
  std::size_t n = 0;
  r.ForEach({}, [&](const MessageView& m) {
    EXPECT_EQ(m.step, n);
    return ++n, true;
  });
  EXPECT_EQ(n, std::size_t{kBatches * kPerBatch});
}

}  // namespace
}  // namespace microdex::record
