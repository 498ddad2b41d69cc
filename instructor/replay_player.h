#pragma once
// Republishes a recorded session over DDS, paced by the recorded receive times, so that an
// instructor console mirrors it as if it were live. Pacing goes through one PlayerClock (play,
// pause, speed, step), which the terminal keys and the tests drive.

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/net/dds_context.h"
#include "common/record/session_reader.h"

namespace microdex::instructor {

// Session time (recorded receive time, ns) against wall time: playing at a speed, or paused.
// Thread-safe: the keys change it from another thread than the player's.
class PlayerClock {
 public:
  using NowFn = std::int64_t (*)();  // monotonic wall time, ns
  // `now`: the wall clock (CLOCK_MONOTONIC by default; tests inject their own).
  PlayerClock(std::int64_t session_start_ns, double speed, NowFn now = nullptr);
  // Wall time now (the clock's).
  std::int64_t WallNowNs() const { return now_(); }
  // The session time reached now.
  std::int64_t SessionNowNs() const;
  // Wall time (monotonic) at which session time t is reached; nullopt while paused.
  std::optional<std::int64_t> WallTimeOf(std::int64_t session_ns) const;
  // Session time stays where it is; wall time restarts from now.
  void Restart();
  void SetSpeed(double speed);  // clamped to [1/64, 1024]
  double speed() const;
  void TogglePause();
  bool paused() const;
  // While paused: advance the session time by dt and stay paused.
  void Step(std::int64_t dt_ns);
  // Jumps to session time t, playing or paused; the player goes on from there (Play).
  void Seek(std::int64_t session_ns);
  std::uint64_t seeks() const;  // how many Seek calls so far

 private:
  std::int64_t SessionAtLocked(std::int64_t wall_ns) const;
  NowFn now_;
  mutable std::mutex mutex_;
  std::int64_t anchor_session_ns_;
  std::int64_t anchor_wall_ns_;
  double speed_;
  bool paused_ = false;
  std::uint64_t seeks_ = 0;
};

// Where a recorded station's scene is on this machine: its recorded path if that is a file,
// else the file of the same name in scene_dir (when given); "" when neither is.
std::string FindRecordedScene(const std::string& recorded_path, const std::string& scene_dir);

// The recorded stations whose scene FindRecordedScene does not find with the recorded hash
// (so that a console without the files could not draw it), "STATION: why" each.
std::vector<std::string> MissingRecordedScenes(record::SessionReader& reader,
                                               const std::string& scene_dir);

struct PlayOptions {
  double speed = 1;
  // Each station's scene is sent on SceneDescription (before its first StationInfo) when it is
  // found here (FindRecordedScene) and its files hash to the recorded scene_hash, so that a
  // console without the files draws it (a recording holds no scene files).
  std::string scene_dir;
  std::optional<double> from_s, to_s;  // seconds from the session's first message
  bool republish_cues = false;         // the recorded cue commands are not sent again
  // Before playing, wait up to this long for every topic to have a reader (a console).
  double wait_for_console_s = 5;
};

struct PlayStats {
  std::uint64_t published = 0;
  std::uint64_t undecodable = 0;
  double session_s = 0;  // session time covered (summed over the stretches between seeks)
  std::uint64_t seeks = 0;
  bool console_found = false;
  // Stations whose scene was sent, and those whose scene was not found here or differs from
  // the recorded one ("STATION: why").
  std::vector<std::string> scenes_sent, scenes_missing;
};

// Plays the recording until its end, `stop`, or to_s. A seek of the clock (PlayerClock::Seek)
// goes on from the time sought, backwards or forwards: every station is announced again, from
// a new StationInfo writer (so that a console takes the steps again as a new run's, not as
// repeats), with its latest StationInfo before that time. Throws std::runtime_error for DDS
// failures (profile, ...).
PlayStats Play(record::SessionReader& reader, const net::DdsOptions& dds, const PlayOptions& o,
               PlayerClock& clock, const std::atomic<bool>& stop);

}  // namespace microdex::instructor
