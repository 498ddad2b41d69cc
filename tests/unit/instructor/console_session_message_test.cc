// The console page's recording and replay commands, decoded (instructor/console_session.h).
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "instructor/console_session.h"

namespace microdex::instructor {
namespace {

using Verb = SessionCommand::Verb;

std::string Refusal(const std::string& message) {
  try {
    ParseSessionMessage(message);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SessionMessage, RecordStartTakesAnOptionalNameAndAddsDb) {
  EXPECT_EQ(ParseSessionMessage("record start").verb, Verb::kRecordStart);
  EXPECT_EQ(ParseSessionMessage("record start").file, "");
  EXPECT_EQ(ParseSessionMessage("record start lesson-1").file, "lesson-1.db");
  EXPECT_EQ(ParseSessionMessage("record start lesson_1.db").file, "lesson_1.db");
  EXPECT_EQ(ParseSessionMessage("record stop").verb, Verb::kRecordStop);
}

TEST(SessionMessage, ReplayTakesFileSpeedAndStart) {
  const SessionCommand c = ParseSessionMessage("replay play a.db 4 2.5");
  EXPECT_EQ(c.verb, Verb::kReplayPlay);
  EXPECT_EQ(c.file, "a.db");
  EXPECT_DOUBLE_EQ(c.speed, 4);
  EXPECT_DOUBLE_EQ(c.from_s, 2.5);
  EXPECT_DOUBLE_EQ(ParseSessionMessage("replay play a.db").speed, 1);
  EXPECT_EQ(ParseSessionMessage("replay pause").verb, Verb::kReplayPause);
  EXPECT_EQ(ParseSessionMessage("replay stop").verb, Verb::kReplayStop);
  EXPECT_DOUBLE_EQ(ParseSessionMessage("replay speed 0.25").speed, 0.25);
  const SessionCommand seek = ParseSessionMessage("replay seek 12.5");
  EXPECT_EQ(seek.verb, Verb::kReplaySeek);
  EXPECT_DOUBLE_EQ(seek.from_s, 12.5);
  EXPECT_DOUBLE_EQ(ParseSessionMessage("replay seek 0").from_s, 0);
  const SessionCommand add = ParseSessionMessage("replay add b.db");
  EXPECT_EQ(add.verb, Verb::kReplayAdd);
  EXPECT_EQ(add.file, "b.db");
  EXPECT_NE(Refusal("replay add").find("replay add: expected FILE"), std::string::npos);
  EXPECT_NE(Refusal("replay add ../b.db").find("replay add: FILE '../b.db' starts with '.'"),
            std::string::npos);
  EXPECT_NE(Refusal("replay add b.db 2").find("unexpected '2'"), std::string::npos);
}

TEST(SessionMessage, RecordDeleteTakesOneRecordingOfTheFolder) {
  const SessionCommand c = ParseSessionMessage("record delete lesson-1.db");
  EXPECT_EQ(c.verb, Verb::kRecordDelete);
  EXPECT_EQ(c.file, "lesson-1.db");
  EXPECT_NE(Refusal("record delete").find("expected FILE"), std::string::npos);
  EXPECT_NE(Refusal("record delete ../../etc/x.db").find("starts with '.'"), std::string::npos);
  EXPECT_NE(Refusal("record delete /etc/passwd").find("has a character"), std::string::npos);
  EXPECT_NE(Refusal("record delete notes.txt").find("does not end in .db"), std::string::npos);
  EXPECT_NE(Refusal("record delete a.db b.db").find("unexpected 'b.db'"), std::string::npos);
  const SessionCommand r = ParseSessionMessage("record rename a.db lesson-2");
  EXPECT_EQ(r.verb, Verb::kRecordRename);
  EXPECT_EQ(r.file, "a.db");
  EXPECT_EQ(r.name, "lesson-2.db");
  EXPECT_EQ(ParseSessionMessage("record rename a.db b.db").name, "b.db");
  EXPECT_NE(Refusal("record rename a.db").find("expected FILE NAME"), std::string::npos);
  EXPECT_NE(Refusal("record rename a.db ../b").find("NAME '../b' starts with '.'"),
            std::string::npos);
  EXPECT_NE(Refusal("record rename a.db b c").find("unexpected 'c'"), std::string::npos);
}

TEST(SessionMessage, NamesThatLeaveTheFolderOrAreNotRecordingsAreRefused) {
  EXPECT_NE(Refusal("record start ../up").find("NAME '../up' starts with"), std::string::npos);
  EXPECT_NE(Refusal("record start a/b").find("has a character"), std::string::npos);
  EXPECT_NE(Refusal("record start .hidden").find("starts with '.'"), std::string::npos);
  EXPECT_NE(Refusal("replay play /etc/passwd").find("FILE"), std::string::npos);
  EXPECT_NE(Refusal("replay play notes.txt").find("does not end in .db"), std::string::npos);
  EXPECT_NE(Refusal("record start " + std::string(100, 'a')).find("longer than 96"),
            std::string::npos);
  EXPECT_EQ(CheckRecordingName("session-20261203-081500.db"), "");
  EXPECT_NE(CheckRecordingName(".db"), "");
}

TEST(SessionMessage, BadNumbersAndWordsAreRefusedWithTheReason) {
  EXPECT_NE(Refusal("replay play a.db fast").find("SPEED 'fast' is not a number"),
            std::string::npos);
  EXPECT_NE(Refusal("replay play a.db nan").find("is not a number"), std::string::npos);
  EXPECT_NE(Refusal("replay speed 2000").find("outside"), std::string::npos);
  EXPECT_NE(Refusal("replay speed 0").find("outside"), std::string::npos);
  EXPECT_NE(Refusal("replay play a.db 1 -3").find("below 0"), std::string::npos);
  EXPECT_NE(Refusal("replay play").find("expected FILE"), std::string::npos);
  EXPECT_NE(Refusal("replay seek").find("expected AT_S"), std::string::npos);
  EXPECT_NE(Refusal("replay seek -1").find("below 0"), std::string::npos);
  EXPECT_NE(Refusal("replay seek end").find("AT_S 'end' is not a number"), std::string::npos);
  EXPECT_NE(Refusal("record stop now").find("unexpected 'now'"), std::string::npos);
  EXPECT_NE(Refusal("record begin").find("expected 'record start"), std::string::npos);
  EXPECT_NE(Refusal("replay rewind").find("expected 'replay play"), std::string::npos);
  EXPECT_NE(Refusal("cue all convergent 300").find("unknown message"), std::string::npos);
  EXPECT_TRUE(IsSessionMessage("record stop"));
  EXPECT_TRUE(IsSessionMessage("  replay pause"));
  EXPECT_FALSE(IsSessionMessage("cue st-1 convergent 300"));
  EXPECT_FALSE(IsSessionMessage("recording"));
}

}  // namespace
}  // namespace microdex::instructor
