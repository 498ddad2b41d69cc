// The SceneDescription topic between a writer (as a station writes it) and an Instructor over
// DDS on loopback: a sound description is kept with its hash; one whose files do not match the
// hash it carries, or with a path that leaves its folder, is refused with the reason (logged
// and kept as the station's scene_error), and a later sound one replaces the refusal.
#include <gtest/gtest.h>

#include <chrono>

#include "common/net/dds_context.h"
#include "common/net/topics.h"
#include "common/scene/scene.h"
#include "common/view/scene_description_msg.h"
#include "common/view/scene_files.h"
#include "instructor/instructor.h"
#include "scene_descriptionPubSubTypes.h"
#include "tests/integration/process.h"

namespace microdex {
namespace {

using namespace std::chrono_literals;
using testing::WaitUntil;

constexpr int kDomain = 87;

msg::SceneDescription ToMsg(const std::string& station, const view::SceneFiles& d) {
  return view::ToSceneDescription(d, station, "test", 0);
}

TEST(SceneDescription, KeptWhenSoundRefusedWithTheReasonOtherwise) {
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.domain_id = kDomain;
  instructor::InstructorOptions options;
  options.dds = dds;
  instructor::Instructor console(options);
  net::DdsContext station(dds);
  auto* writer = station.CreateWriter<msg::SceneDescriptionPubSubType>(net::kSceneDescriptionTopic);

  const view::SceneFiles good =
      view::CollectSceneFiles(scene::LoadScene("assets/scenes/needle_through_tissue.yaml"));
  view::SceneFiles tampered = good;
  tampered.files.back().bytes[0] ^= 1;  // one bit changed after hashing
  view::SceneFiles escaping = good;
  escaping.files.back().path = "../../etc/cron.d/x";
  escaping.hash = view::HashSceneFiles(escaping.scene_path, escaping.files);

  msg::SceneDescription m = ToMsg("good", good);
  ASSERT_TRUE(writer->write(&m));
  m = ToMsg("tampered", tampered);
  ASSERT_TRUE(writer->write(&m));
  m = ToMsg("escaping", escaping);
  ASSERT_TRUE(writer->write(&m));

  auto has = [&](const std::string& id, auto&& pred) {
    return WaitUntil(
        [&] {
          const auto v = console.Station(id);
          return v && pred(*v);
        },
        10s);
  };
  ASSERT_TRUE(
      has("good", [](const instructor::StationView& v) { return v.scene_files != nullptr; }));
  const auto g = console.Station("good");
  EXPECT_EQ(g->scene_files->hash, good.hash);
  EXPECT_EQ(g->scene_files->files.size(), good.files.size());
  EXPECT_EQ(g->scene_error, "");

  ASSERT_TRUE(
      has("tampered", [](const instructor::StationView& v) { return !v.scene_error.empty(); }));
  const auto t = console.Station("tampered");
  EXPECT_EQ(t->scene_files, nullptr);
  EXPECT_NE(t->scene_error.find("hash"), std::string::npos) << t->scene_error;

  ASSERT_TRUE(
      has("escaping", [](const instructor::StationView& v) { return !v.scene_error.empty(); }));
  EXPECT_NE(console.Station("escaping")->scene_error.find(".."), std::string::npos);

  // The station sends a sound one later (same key): kept, the refusal cleared.
  m = ToMsg("tampered", good);
  ASSERT_TRUE(writer->write(&m));
  ASSERT_TRUE(
      has("tampered", [](const instructor::StationView& v) { return v.scene_files != nullptr; }));
  EXPECT_EQ(console.Station("tampered")->scene_error, "");
}

}  // namespace
}  // namespace microdex
