// microdex-replay: replays a recorded session over DDS, re-simulates it and checks its state
// hashes, or exports it (README.md in this folder, "Replay").

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>

#include "common/net/app_cli.h"
#include "common/scores/experiment.h"
#include "instructor/console_server.h"
#include "instructor/instructor.h"
#include "instructor/replay_export.h"
#include "instructor/replay_player.h"
#include "instructor/replay_resim.h"
#include "instructor/scores_report.h"

namespace {

std::atomic<bool> g_stop{false};

// The terminal in raw mode while it is alive (keys without Enter), restored after.
class RawTerminal {
 public:
  RawTerminal() {
    if (!isatty(STDIN_FILENO) || tcgetattr(STDIN_FILENO, &saved_) != 0) return;
    termios raw = saved_;
    raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 1;  // read() returns after 0.1 s without a key
    active_ = tcsetattr(STDIN_FILENO, TCSANOW, &raw) == 0;
  }
  ~RawTerminal() {
    if (active_) tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
  }
  RawTerminal(const RawTerminal&) = delete;
  RawTerminal& operator=(const RawTerminal&) = delete;
  bool active() const { return active_; }

 private:
  termios saved_{};
  bool active_ = false;
};

// --render: node on instructor/page/render.mjs against the replay's own console, its standard
// input a pipe (closing it ends the rendering) and its standard output a pipe (its first line
// says the page is open).
struct Renderer {
  pid_t pid = -1;
  int to_child = -1;
  int from_child = -1;
};

Renderer StartRenderer(std::uint16_t port, const std::string& dir, double every_ms, int stations,
                       double speed) {
  int in[2], out[2];
  if (pipe(in) != 0) throw std::runtime_error("--render: cannot make a pipe");
  if (pipe(out) != 0) {
    close(in[0]);
    close(in[1]);
    throw std::runtime_error("--render: cannot make a pipe");
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  for (int fd : {in[0], in[1], out[0], out[1]}) posix_spawn_file_actions_addclose(&actions, fd);
  const std::string script = std::string(MICRODEX_SOURCE_DIR) + "/instructor/page/render.mjs";
  std::vector<std::string> args = {"node",       script,
                                   "--url",      "http://127.0.0.1:" + std::to_string(port) + "/",
                                   "--out",      dir,
                                   "--every-ms", std::to_string(static_cast<long>(every_ms)),
                                   "--stations", std::to_string(stations),
                                   "--speed",    std::to_string(speed)};
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  Renderer r;
  const int rc = posix_spawnp(&r.pid, "node", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(in[0]);
  close(out[1]);
  if (rc != 0) {
    close(in[1]);
    close(out[0]);
    throw std::runtime_error("--render: cannot run node (it draws through Chromium)");
  }
  r.to_child = in[1];
  r.from_child = out[0];
  return r;
}

// Waits up to timeout_s for the renderer's first line; false if it exits or says nothing.
bool AwaitRendererReady(const Renderer& r, double timeout_s) {
  std::string line;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    pollfd p{r.from_child, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    char c = 0;
    if (read(r.from_child, &c, 1) != 1) return false;
    if (c == '\n') return line.find("page open") != std::string::npos;
    line += c;
  }
  return false;
}

// Closes the renderer's input (the replay is over), relays what it prints and returns its
// exit status.
int FinishRenderer(Renderer& r) {
  close(r.to_child);
  char buf[512];
  ssize_t n = 0;
  while ((n = read(r.from_child, buf, sizeof buf)) > 0) {
    std::fwrite(buf, 1, static_cast<std::size_t>(n), stdout);
  }
  close(r.from_child);
  int status = 0;
  if (waitpid(r.pid, &status, 0) != r.pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Prints "PROGRAM: first problem (and N more)" and returns 2, or 0 without problems.
int ReportProblems(const microdex::record::SessionReader& reader) {
  const auto& p = reader.problems();
  if (p.empty()) return 0;
  if (p.size() == 1) {
    std::fprintf(stderr, "microdex-replay: %s\n", p[0].c_str());
  } else {
    std::fprintf(stderr, "microdex-replay: %s (and %zu more problems)\n", p[0].c_str(),
                 p.size() - 1);
  }
  return 2;
}

}  // namespace

// Errors are caught around parsing and the run; what could escape is an allocation failure
// while setting up, which ends the process as it should.
int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  const microdex::net::StopSignals stop_signals;
  using namespace microdex;
  std::string file;
  double speed = 1;
  std::optional<double> from_s, to_s;
  bool resimulate = false;
  std::string export_dir, summary_file, scene_dir;
  net::DdsOptions dds;
  dds.profile_file = net::DefaultDdsProfileFile();
  dds.participant_name = "microdex-replay";
  CLI::App app{
      "microdex-replay: replays a recorded session (microdex-instructor --record) over DDS, "
      "re-simulates it and checks every state hash, or exports it"};
  app.add_option("file", file, "the recording (SQLite); not with --db");
  std::string db_url, curves_dir, experiment, report_dir, course;
  app.add_option("--db", db_url,
                 "scores database (SQLite file or postgresql:// URL) for --curves or "
                 "--experiment, instead of a recording");
  app.add_option("--curves", curves_dir,
                 "--db: write each trainee's learning curve (score by session, per scene) as "
                 "PNG into this folder");
  app.add_option("--course", course, "--curves: only this course's sessions");
  app.add_option("--experiment", experiment,
                 "--db: report on this experiment (its YAML file, or its name): per-condition "
                 "learning curves (PNG) and effect sizes (Markdown), into --report DIR");
  app.add_option("--report", report_dir, "--experiment: output folder (default: report)");
  app.add_option("--speed", speed, "replay speed (1: real time; 4: four times faster)");
  app.add_option("--from", from_s, "start this many seconds into the session");
  app.add_option("--to", to_s, "stop this many seconds into the session");
  double wait_console_s = 5;
  app.add_option("--wait-for-console", wait_console_s,
                 "before playing, wait up to S seconds for a console to listen (default 5)");
  app.add_flag("--resimulate", resimulate,
               "re-run every station from its scene, seed and recorded inputs and compare the "
               "state hash of every step; exit 0 when all match, 1 naming the station and the "
               "first divergent step");
  app.add_option("--scene-dir", scene_dir,
                 "folder to look for a scene whose recorded path does not exist (by its file "
                 "name): --resimulate runs it; a replay sends it to the consoles, which then "
                 "need none of the scene's files");
  app.add_option("--export-csv", export_dir, "write one CSV per topic into this folder");
  app.add_option("--summary", summary_file, "write the session summary (Markdown) to this file");
  std::string render_dir;
  double render_every_s = 1.0;
  app.add_option("--render", render_dir,
                 "while replaying, draw the session through the console page in headless "
                 "Chromium into this folder: the whole console every --render-every seconds of "
                 "the session (console_NNNNN.png, index.csv), then each station's view "
                 "enlarged at the end (station_ID.png)");
  app.add_option("--render-every", render_every_s,
                 "--render: seconds of the session between console pictures (default 1)");
  net::AddDdsOptions(app, dds);
  if (const std::optional<int> status = net::ParseCommandLine(app, argc, argv, "microdex-replay")) {
    return *status;
  }
  if (!(wait_console_s >= 0 && wait_console_s <= 600)) {
    std::fprintf(stderr, "microdex-replay: --wait-for-console: expected 0..600 s\n");
    return 2;
  }
  if (!(render_every_s >= 0.05 && render_every_s <= 3600)) {
    std::fprintf(stderr, "microdex-replay: --render-every: expected 0.05..3600 s\n");
    return 2;
  }
  if (!(speed > 0) || speed > 1024) {
    std::fprintf(stderr, "microdex-replay: --speed: expected 0 < X <= 1024\n");
    return 2;
  }
  if ((from_s && !(*from_s >= 0)) || (to_s && !(*to_s >= 0)) ||
      (from_s && to_s && *to_s < *from_s)) {
    std::fprintf(stderr, "microdex-replay: --from/--to: expected 0 <= from <= to (seconds)\n");
    return 2;
  }
  if (!db_url.empty()) {
    if (!file.empty()) {
      std::fprintf(stderr, "microdex-replay: --db: give either a recording or --db, not both\n");
      return 2;
    }
    if (curves_dir.empty() && experiment.empty()) {
      std::fprintf(stderr, "microdex-replay: --db: expected --curves DIR and/or --experiment\n");
      return 2;
    }
    try {
      const auto db = scores::ScoresDb::Open(db_url);
      if (!curves_dir.empty()) {
        for (const auto& f : instructor::WriteLearningCurves(*db, course, curves_dir)) {
          std::printf("%s\n", f.c_str());
        }
      }
      if (!experiment.empty()) {
        std::string name = experiment;
        const auto ends_with = [&](const char* ext) {
          const std::string e(ext);
          return name.size() > e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
        };
        if (ends_with(".yaml") || ends_with(".yml")) name = scores::ReadExperiment(experiment).name;
        const auto r = instructor::WriteExperimentReport(
            *db, name, report_dir.empty() ? std::string("report") : report_dir);
        for (const auto& f : r.files) std::printf("%s\n", f.c_str());
        std::printf("best condition: %s\n", r.best.c_str());
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "microdex-replay: %s\n", e.what());
      return 2;
    }
    return 0;
  }
  if (file.empty()) {
    std::fprintf(stderr, "microdex-replay: expected a recording FILE.db (or --db URL)\n");
    return 2;
  }
  stop_signals.Watch(g_stop);
  try {
    record::SessionReader reader(file);
    if (resimulate) {
      instructor::ResimOptions ro;
      ro.scene_dir = scene_dir;
      const bool tty = isatty(STDERR_FILENO) != 0;
      const auto t0 = std::chrono::steady_clock::now();
      if (tty) {
        ro.progress = [&](const std::string& station, std::uint64_t done, std::uint64_t all) {
          const double el =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          const double eta = done > 0 && all > done
                                 ? el / static_cast<double>(done) * static_cast<double>(all - done)
                                 : 0;
          std::fprintf(stderr, "\r%s: %llu/%llu steps, ETA %.0f s   ", station.c_str(),
                       static_cast<unsigned long long>(done), static_cast<unsigned long long>(all),
                       eta);
        };
      }
      const auto results = instructor::Resimulate(reader, ro);
      if (tty) std::fprintf(stderr, "\r%60s\r", "");
      int status = 0;
      for (const auto& r : results) {
        std::printf("%s\n", instructor::FormatResimResult(r).c_str());
        if (r.diverged) status = 1;
      }
      std::fflush(stdout);
      if (results.empty()) {
        std::fprintf(stderr, "microdex-replay: %s: no station to re-simulate\n", file.c_str());
        return 2;
      }
      if (status != 0) {
        for (const auto& r : results) {
          if (r.diverged) {
            std::fprintf(stderr, "microdex-replay: %s: station %s diverges at step %llu\n",
                         file.c_str(), r.station.c_str(),
                         static_cast<unsigned long long>(r.divergent_step));
            return 1;
          }
        }
      }
      for (const auto& r : results) {
        if (!r.problem.empty()) {
          std::fprintf(stderr, "microdex-replay: %s: station %s: %s\n", file.c_str(),
                       r.station.c_str(), r.problem.c_str());
          return 2;
        }
      }
      return ReportProblems(reader);
    }
    if (!export_dir.empty() || !summary_file.empty()) {
      if (!export_dir.empty()) {
        const std::size_t rows = instructor::ExportCsv(reader, export_dir);
        std::printf("%zu rows written to %s/\n", rows, export_dir.c_str());
      }
      if (!summary_file.empty()) {
        std::ofstream f(summary_file);
        f << instructor::SessionSummaryMarkdown(reader);
        if (!f) throw std::runtime_error(summary_file + ": cannot write");
        std::printf("summary written to %s\n", summary_file.c_str());
      }
      std::fflush(stdout);
      return ReportProblems(reader);
    }
    if (std::string why = dds.Validate(); !why.empty()) {
      std::fprintf(stderr, "microdex-replay: --%s\n", why.c_str());
      return 2;
    }
    // Replay over DDS.
    const auto [first_ns, last_ns] = reader.TimeRange();
    const std::int64_t start_ns =
        first_ns + (from_s ? static_cast<std::int64_t>(*from_s * 1e9) : 0);
    instructor::PlayerClock clock(start_ns, speed);
    instructor::PlayOptions po;
    po.speed = speed;
    po.from_s = from_s;
    po.to_s = to_s;
    po.wait_for_console_s = wait_console_s;
    po.scene_dir = scene_dir;
    // --render: a console of the replay's own (the instructor's registry and page server on
    // loopback, subscribed like any console) and a headless browser drawing its page.
    std::unique_ptr<instructor::Instructor> render_console;
    std::unique_ptr<instructor::ConsoleServer> render_server;
    Renderer renderer;
    if (!render_dir.empty()) {
      const std::size_t stations = reader.Stations().size();
      if (stations == 0) {
        std::fprintf(stderr, "microdex-replay: %s: --render: no station in the recording\n",
                     file.c_str());
        return 2;
      }
      if (const auto missing = instructor::MissingRecordedScenes(reader, scene_dir);
          !missing.empty()) {
        std::fprintf(stderr, "microdex-replay: %s: --render: station %s\n", file.c_str(),
                     missing.front().c_str());
        return 2;
      }
      instructor::InstructorOptions io;
      io.dds = dds;
      io.dds.participant_name = "microdex-replay-render";
      io.issuer = "microdex-replay --render";
      io.receive_inputs = true;  // so that every replayed writer finds its reader at once
      render_console = std::make_unique<instructor::Instructor>(io);
      render_server = std::make_unique<instructor::ConsoleServer>(*render_console, "127.0.0.1", 0,
                                                                  instructor::DefaultWebDir(),
                                                                  instructor::ConsoleSecurity{});
      renderer = StartRenderer(render_server->port(), render_dir, render_every_s * 1e3 / speed,
                               static_cast<int>(stations), speed);
      if (!AwaitRendererReady(renderer, 60)) {
        const int rc = FinishRenderer(renderer);
        std::fprintf(stderr, "microdex-replay: --render %s: the console page did not open (%d)\n",
                     render_dir.c_str(), rc);
        return 2;
      }
      std::printf("rendering into %s: the console every %g s of the session\n", render_dir.c_str(),
                  render_every_s);
    }
    std::printf(
        "replaying %s: %.1f s at %gx on domain %d (keys: space pause, n step 0.1 s, "
        "[ / ] seek 5 s back / on, +/- speed, q quit)\n",
        file.c_str(), static_cast<double>(last_ns - first_ns) * 1e-9, speed, dds.domain_id);
    std::fflush(stdout);
    std::atomic<bool> done{false};
    const std::int64_t session_first_ns = first_ns, session_last_ns = last_ns;
    std::thread keys([&] {
      RawTerminal term;
      if (!term.active()) return;
      while (!done.load() && !g_stop.load()) {
        char c = 0;
        if (read(STDIN_FILENO, &c, 1) != 1) continue;
        if (c == ' ') {
          clock.TogglePause();
          std::printf("%s\n", clock.paused() ? "paused" : "playing");
        } else if (c == 'n') {
          clock.Step(100'000'000);
        } else if (c == '[' || c == ']') {
          const std::int64_t to = std::clamp<std::int64_t>(
              clock.SessionNowNs() + (c == '[' ? -5'000'000'000 : 5'000'000'000), session_first_ns,
              session_last_ns);
          clock.Seek(to);
          std::printf("at %.1f s\n", static_cast<double>(to - session_first_ns) * 1e-9);
        } else if (c == '+') {
          clock.SetSpeed(clock.speed() * 2);
          std::printf("speed %gx\n", clock.speed());
        } else if (c == '-') {
          clock.SetSpeed(clock.speed() / 2);
          std::printf("speed %gx\n", clock.speed());
        } else if (c == 'q') {
          g_stop = true;
        }
        std::fflush(stdout);
      }
    });
    instructor::PlayStats stats;
    try {
      stats = instructor::Play(reader, dds, po, clock, g_stop);
    } catch (...) {
      done = true;
      keys.join();
      throw;
    }
    done = true;
    keys.join();
    std::printf("replayed %llu samples, %.1f s of the session\n",
                static_cast<unsigned long long>(stats.published), stats.session_s);
    for (const std::string& m : stats.scenes_missing) {
      std::printf("scene not sent: station %s\n", m.c_str());
    }
    std::fflush(stdout);
    if (renderer.pid > 0) {
      const int rc = FinishRenderer(renderer);
      std::fflush(stdout);
      if (rc != 0) {
        std::fprintf(stderr, "microdex-replay: --render %s: the browser failed (exit %d)\n",
                     render_dir.c_str(), rc);
        return 2;
      }
    }
    if (stats.undecodable > 0) {
      std::fprintf(stderr, "microdex-replay: %s: %llu samples do not decode (skipped)\n",
                   file.c_str(), static_cast<unsigned long long>(stats.undecodable));
      return 2;
    }
    return ReportProblems(reader);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-replay: %s\n", e.what());
    return 2;
  }
}
