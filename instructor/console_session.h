#pragma once
// The console's session controls (microdex-instructor --record-dir DIR): start and stop a
// recording into DIR, list DIR's recordings, and replay one into this console, with pause,
// speed and stop. The page sends them over its WebSocket:
//
//   record start [NAME]                 NAME.db in DIR (default session-YYYYMMDD-HHMMSS.db, UTC)
//   record stop
//   record delete FILE                  FILE (and SQLite's -wal, -shm) removed from DIR
//   record rename FILE NAME             FILE renamed NAME.db in DIR
//   replay play FILE [SPEED [FROM_S]]   FILE: a recording in DIR, by name
//   replay add FILE                     FILE plays alongside, from the replay's position
//   replay pause                        pause or resume
//   replay speed SPEED                  1/64 … 1024
//   replay seek AT_S                    on from AT_S s after the recordings' starts
//   replay stop
//
// The files of one replay (play, then add) share its transport: each plays from its own
// start, at one position, speed and pause; a seek moves them all (one that had ended plays
// again when sought back into it), stop stops them all.
//
// A replay republishes the recording over DDS (replay_player.h) from a participant of this
// process, in the console's domain and partition, so the console mirrors the recorded stations
// as it mirrors live ones; the recorded scenes are sent when found (PlayOptions::scene_dir).
// Refused, with the reason: a replay while recording or replaying (add one to it instead), a
// file added that is playing already, shares a station with the replay, or is shorter than its
// position, a recording while
// replaying, a replay of a station that is alive here now (its samples would mix with the live
// ones), a replay from a secure console (its participant has no identity of the course: use
// microdex-replay), a name with a folder in it or that exists already, the deletion of the
// file being recorded or replayed.
//
// Threads: Handle and StatusJson run on the view server's thread; the replay on a thread of
// its own (Play), stopped by the destructor.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/net/dds_context.h"
#include "instructor/console_message.h"
#include "instructor/instructor.h"
#include "instructor/replay_player.h"

namespace microdex::instructor {

// One recording of DIR, as listed.
struct RecordingFile {
  std::string name;
  std::uintmax_t bytes = 0;
  double seconds = 0;  // first to last message
  std::vector<std::string> stations;
  std::string error;  // the file does not open as a recording (why)
};

class SessionControl {
 public:
  static constexpr std::size_t kMaxListed = 50;  // the newest recordings listed

  // `dds`: the console's own options (domain, partition, profile) for the replay's
  // participant; `scene_dir`: where a replay looks for a recorded scene by name. Throws
  // std::runtime_error when DIR is not a folder that can be made.
  SessionControl(Instructor& instructor, const std::string& record_dir, net::DdsOptions dds,
                 std::string scene_dir = "");
  ~SessionControl();
  SessionControl(const SessionControl&) = delete;
  SessionControl& operator=(const SessionControl&) = delete;

  // Carries out a command; returns the reply (JSON) or throws std::invalid_argument (refused:
  // why) / std::runtime_error (the file could not be made).
  std::string Handle(const SessionCommand& command);
  // The "session" object of the station list: the folder, the recording, the replay, the
  // recordings (listed again at most once a second).
  std::string StatusJson();
  // DIR's recordings, newest first (at most kMaxListed).
  std::vector<RecordingFile> Recordings();
  const std::string& record_dir() const { return dir_; }
  bool replaying() const;

 private:
  // One file of the replay.
  struct Replay {
    std::string file;
    std::int64_t first_ns = 0, last_ns = 0;
    std::vector<std::string> stations;
    std::unique_ptr<PlayerClock> clock;
    std::atomic<bool> stop{false};
    std::atomic<bool> done{false};
    std::uint64_t published = 0;  // over its plays (a seek back after its end plays it again)
    std::vector<std::string> scenes_missing;  // once done
    std::string error;                        // once done: why it failed ("" when it played)
    std::thread thread;
    double length_s() const { return static_cast<double>(last_ns - first_ns) * 1e-9; }
  };
  void EndReplay();    // joins the finished members' threads
  void StopReplays();  // stops and joins every member
  // FILE of DIR opened for a replay, with the checks every member passes (a recording, not
  // empty, no station alive here); `verb` names the command in the refusals.
  std::unique_ptr<record::SessionReader> OpenForReplay(const std::string& verb,
                                                       const std::string& file, Replay& r);
  // Plays r from from_s on a thread of its own, paced by r.clock.
  void Launch(Replay& r, std::unique_ptr<record::SessionReader> reader, double from_s);
  double Position() const;  // of the replay: its members at one position
  double Length() const;    // its longest member's
  std::string StartRecording(const std::string& name);
  std::string StartReplay(const SessionCommand& c);
  std::string AddReplay(const SessionCommand& c);
  std::string Transport(const SessionCommand& c);  // pause, speed, seek, stop
  std::string DeleteRecording(const std::string& name);
  std::string RenameRecording(const std::string& from, const std::string& to);
  // Why FILE may not be deleted or renamed now ("" when it may): recorded or playing.
  std::string InUse(const std::string& name) const;

  Instructor& instructor_;
  std::string dir_;
  net::DdsOptions dds_;
  std::string scene_dir_;
  std::vector<std::unique_ptr<Replay>> replays_;  // the running or the last replay's files
  std::string last_recording_;                    // the file of the last recording stopped
  std::optional<record::RecorderStats> last_recording_stats_;
  struct Cached {
    std::filesystem::file_time_type mtime;
    std::uintmax_t bytes = 0;
    RecordingFile file;
  };
  std::map<std::string, Cached> cache_;  // by name
  std::vector<RecordingFile> listed_;
  std::int64_t next_list_ns_ = 0;
};

}  // namespace microdex::instructor
