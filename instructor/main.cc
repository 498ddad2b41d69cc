// microdex-instructor: the instructor console, headless text view (README.md
// "Command-line contracts").

#include <termios.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <thread>

#include "common/net/app_cli.h"
#include "instructor/console_server.h"
#include "instructor/cue_spec.h"
#include "instructor/instructor.h"
#include "instructor/scores_writer.h"

namespace {
std::atomic<bool> g_stop{false};

// --add-user NAME: the password from stdin (one line; a terminal does not echo it).
int AddConsoleUser(const std::string& users_file, const std::string& name,
                   const std::string& role_text) {
  if (users_file.empty()) {
    std::fprintf(stderr,
                 "microdex-instructor: --add-user: expected --users FILE or --security DIR\n");
    return 2;
  }
  const bool tty = isatty(0) != 0;
  termios saved{};
  if (tty) {
    std::fprintf(stderr, "password for %s: ", name.c_str());
    tcgetattr(0, &saved);
    termios quiet = saved;
    quiet.c_lflag &= ~static_cast<tcflag_t>(ECHO);
    tcsetattr(0, TCSANOW, &quiet);
  }
  std::string password;
  std::getline(std::cin, password);
  if (tty) {
    tcsetattr(0, TCSANOW, &saved);
    std::fprintf(stderr, "\n");
  }
  if (!password.empty() && password.back() == '\r') password.pop_back();
  try {
    microdex::instructor::AddUser(users_file, name, microdex::instructor::ParseRole(role_text),
                                  password);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-instructor: --add-user: %s\n", e.what());
    return 2;
  }
  std::printf("%s: user %s (%s) added\n", users_file.c_str(), name.c_str(), role_text.c_str());
  return 0;
}

}  // namespace

// Errors are caught around parsing and the run; what could escape is an allocation failure
// while setting up, which ends the process as it should.
int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  const microdex::net::StopSignals stop_signals;

  using namespace microdex;
  instructor::InstructorOptions o;
  o.dds.profile_file = net::DefaultDdsProfileFile();
  o.dds.participant_name = "microdex-instructor";
  bool headless = false;
  double duration_s = 0;
  double table_period_s = 1;
  std::vector<std::string> cue_texts;
  int http_port = -1;
  std::string http_address = "127.0.0.1";
  CLI::App app{"microdex-instructor: discovers stations, mirrors their state, sends cues"};
  app.add_flag("--headless", headless, "text view on stdout");
  app.add_option("--http", http_port,
                 "serve the live console on http://ADDRESS:PORT/ (0: any free port)");
  app.add_option("--http-address", http_address, "address the console binds (127.0.0.1)");
  app.add_option("--duration", duration_s, "stop after S seconds (0: until SIGINT/SIGTERM)");
  app.add_option(
      "--cue", cue_texts,
      std::string("STATION:KIND:PARAM[@SECONDS] (PARAM 'off': switch off), KIND one of ") +
          microdex::cues::CueKindNames() + "; STATION may be 'all'");
  app.add_option("--table-period", table_period_s, "seconds between tables (0: only at the end)");
  app.add_option("--issuer", o.issuer, "name of this console in the cues it sends");
  app.add_flag("--inputs", o.receive_inputs,
               "take every station's 1 kHz DeviceInput without recording (counted in the table; "
               "always taken with --record)");
  microdex::net::AddDdsOptions(app, o.dds);
  app.add_option("--record", o.record_file,
                 "record the session (every station's topics, the cues sent) to this new SQLite "
                 "file; see microdex-replay");
  std::string record_dir, scene_dir;
  app.add_option("--record-dir", record_dir,
                 "recording and replay from the console page (--http): recordings start and "
                 "stop there, into this folder (made when missing), and replay from it");
  app.add_option("--scene-dir", scene_dir,
                 "with --record-dir: where a replay looks for a recorded scene by its file name "
                 "when its recorded path is not there");
  std::string db_url, course, experiment_file;
  app.add_option("--db", db_url,
                 "scores database: an SQLite file (one per course; created when missing) or "
                 "postgresql://USER@HOST:PORT/DBNAME");
  app.add_option("--course", course,
                 "course name of the sessions in the scores database (default: the DDS "
                 "partition, else 'default')");
  app.add_option("--experiment", experiment_file,
                 "run the cue experiment of this YAML file (needs --db): assigns the trainees "
                 "to conditions, sends each trial's cues; stops when every trial is scored");
  microdex::net::AddSecurityOption(app, o.dds);
  instructor::ConsoleSecurity web_security;
  std::string add_user, role = "instructor";
  app.add_option("--tls-cert", web_security.tls_cert_file,
                 "console over HTTPS with this PEM certificate (default with --security: "
                 "DIR/console_cert.pem)");
  app.add_option("--tls-key", web_security.tls_key_file, "the certificate's PEM private key");
  app.add_option("--users", web_security.users_file,
                 "console login: the users file (default with --security: DIR/console_users)");
  app.add_option("--session-timeout", web_security.session_idle_s,
                 "console login: a session unused for S seconds ends");
  app.add_option("--add-user", add_user,
                 "add (or replace) console user NAME in the users file, the password read from "
                 "stdin, and exit");
  app.add_option("--role", role, "with --add-user: instructor (sends cues) or observer");
  if (const std::optional<int> status =
          microdex::net::ParseCommandLine(app, argc, argv, "microdex-instructor")) {
    return *status;
  }
  if (!o.dds.security_dir.empty()) {
    const std::string dir = o.dds.security_dir + "/";
    if (web_security.tls_cert_file.empty() && web_security.tls_key_file.empty()) {
      web_security.tls_cert_file = dir + "console_cert.pem";
      web_security.tls_key_file = dir + "console_key.pem";
    }
    if (web_security.users_file.empty()) web_security.users_file = dir + "console_users";
  }
  if (!add_user.empty()) return AddConsoleUser(web_security.users_file, add_user, role);
  if (web_security.tls_cert_file.empty() != web_security.tls_key_file.empty()) {
    std::fprintf(stderr, "microdex-instructor: --tls-cert and --tls-key go together\n");
    return 2;
  }
  if (!web_security.users_file.empty() && web_security.tls_cert_file.empty()) {
    std::fprintf(stderr,
                 "microdex-instructor: --users: the login needs HTTPS (--security DIR, or "
                 "--tls-cert and --tls-key)\n");
    return 2;
  }
  if (!headless && http_port < 0) {
    std::fprintf(stderr, "microdex-instructor: expected --headless and/or --http PORT\n");
    return 2;
  }
  if (!record_dir.empty() && http_port < 0) {
    std::fprintf(stderr,
                 "microdex-instructor: --record-dir: the controls are on the console "
                 "page: expected --http PORT\n");
    return 2;
  }
  o.recording_ready = !record_dir.empty();
  if (http_port > 65535) {
    std::fprintf(stderr, "microdex-instructor: --http: expected a port 0..65535\n");
    return 2;
  }
  if (!(duration_s >= 0) || !(table_period_s >= 0)) {
    std::fprintf(stderr, "microdex-instructor: --duration/--table-period: expected >= 0\n");
    return 2;
  }
  if (std::string why = o.dds.Validate(); !why.empty()) {
    std::fprintf(stderr, "microdex-instructor: --%s\n", why.c_str());
    return 2;
  }
  std::vector<instructor::CueSpec> cues;
  if (const std::string why = microdex::net::CheckSecurityOption(o.dds); !why.empty()) {
    std::fprintf(stderr, "microdex-instructor: %s\n", why.c_str());
    return 2;
  }
  try {
    for (const auto& t : cue_texts) cues.push_back(instructor::ParseCueSpec(t));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-instructor: %s\n", e.what());
    return 2;
  }

  instructor::ScoresWriterOptions scores_options;
  if (!experiment_file.empty() && db_url.empty()) {
    std::fprintf(stderr, "microdex-instructor: --experiment: needs --db URL\n");
    return 2;
  }
  if (!experiment_file.empty()) {
    try {
      scores_options.experiment = scores::ReadExperiment(experiment_file);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "microdex-instructor: %s\n", e.what());
      return 2;
    }
  }
  scores_options.url = db_url;
  scores_options.course =
      !course.empty() ? course : (o.dds.partition.empty() ? "default" : o.dds.partition);
  scores_options.recording = o.record_file;

  stop_signals.Watch(g_stop);

  try {
    instructor::Instructor console(o);
    std::unique_ptr<instructor::SessionControl> session;
    if (!record_dir.empty()) {
      session = std::make_unique<instructor::SessionControl>(console, record_dir, o.dds, scene_dir);
      std::printf("recordings: %s\n", record_dir.c_str());
    }
    std::unique_ptr<instructor::ConsoleServer> web;
    if (http_port >= 0) {
      web = std::make_unique<instructor::ConsoleServer>(console, http_address, http_port,
                                                        instructor::DefaultWebDir(), web_security,
                                                        session.get());
      std::printf("console: %s://%s:%u/\n", web->https() ? "https" : "http", http_address.c_str(),
                  unsigned{web->port()});
    }
    std::unique_ptr<instructor::ScoresWriter> scores_db;
    if (!db_url.empty()) {
      scores_db = std::make_unique<instructor::ScoresWriter>(scores_options, console);
      std::printf("scores database: %s (course %s)\n", scores::RedactUrl(db_url).c_str(),
                  scores_options.course.c_str());
      for (const auto& [trainee, condition] : scores_db->assignment()) {
        std::printf("experiment %s: %s -> %s\n", scores_options.experiment->name.c_str(),
                    trainee.c_str(), condition.c_str());
      }
    }
    // The page's plot of past sessions, from the scores database.
    std::int64_t next_past = 0;
    const auto send_past_scores = [&](std::int64_t now) {
      if (!scores_db || !web || now < next_past) return;
      next_past = now + 2'000'000'000;
      try {
        web->SetPastScores(scores_options.course, scores_db->FinalScores());
      } catch (const std::exception& e) {
        std::fprintf(stderr, "microdex-instructor: scores database: %s\n", e.what());
      }
    };
    const std::int64_t start = instructor::MonotonicNowNs();
    std::int64_t next_table = start + static_cast<std::int64_t>(table_period_s * 1e9);
    std::vector<bool> sent(cues.size(), false);
    std::printf("instructor %s on domain %d%s%s\n", console.session_id().c_str(), o.dds.domain_id,
                o.dds.partition.empty() ? "" : ", partition ", o.dds.partition.c_str());
    std::fflush(stdout);
    for (;;) {
      const std::int64_t now = instructor::MonotonicNowNs();
      const double t = static_cast<double>(now - start) * 1e-9;
      for (std::size_t i = 0; i < cues.size(); ++i) {
        if (!sent[i] && t >= cues[i].at_s) {
          const auto id =
              console.SendCue(cues[i].station, cues[i].kind, cues[i].param, 0, cues[i].off);
          char param[32] = "off";
          if (!cues[i].off) std::snprintf(param, sizeof param, "%g", cues[i].param);
          std::printf("[%7.3f] cue %llu sent: %s %s %s\n", t, static_cast<unsigned long long>(id),
                      cues[i].station.c_str(), cues::CueKindName(cues[i].kind), param);
          sent[i] = true;
        }
      }
      const std::vector<net::TaskEvent> events = console.TakeEvents();
      if (scores_db) {
        for (const std::string& line :
             scores_db->Update(console.Stations(), events, console.TakeFinalScores())) {
          std::printf("[%7.3f] %s\n", t, line.c_str());
        }
      }
      for (const auto& e : events) {
        if (e.kind == net::TaskEventKind::kContactBegin ||
            e.kind == net::TaskEventKind::kContactEnd) {
          continue;  // in the table's contact count; too many to list
        }
        std::printf("[%7.3f] %s %s step %llu", t, e.header.station_id.c_str(),
                    net::TaskEventKindName(e.kind), static_cast<unsigned long long>(e.header.step));
        if (e.cue_id) std::printf(" cue %llu", static_cast<unsigned long long>(e.cue_id));
        if (!e.text.empty()) std::printf(" (%s)", e.text.c_str());
        std::printf("\n");
      }
      send_past_scores(now);
      if (headless && table_period_s > 0 && now >= next_table) {
        std::printf("--- t = %.1f s\n%s", t,
                    instructor::FormatStationTable(console.Stations(), now).c_str());
        if (const std::string rej = instructor::FormatRejected(console.Rejected()); !rej.empty()) {
          std::printf("%s\n", rej.c_str());
        }
        next_table += static_cast<std::int64_t>(table_period_s * 1e9);
      }
      std::fflush(stdout);
      if (g_stop || (duration_s > 0 && t >= duration_s)) break;
      if (scores_db && scores_db->ExperimentDone()) {
        std::printf("[%7.3f] experiment %s: every trial scored\n", t,
                    scores_options.experiment->name.c_str());
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (scores_db) scores_db->Finish(console.Stations());
    const std::int64_t now = instructor::MonotonicNowNs();
    std::printf("--- final\n%s", instructor::FormatStationTable(console.Stations(), now).c_str());
    for (const auto& v : console.Stations()) {
      if (!v.score.latest) continue;
      const auto& s = *v.score.latest;
      // "contact": needle on the wall, or a thread/tissue fault (overstretch, pressing too hard).
      char clearance[64] = "";
      if (std::isfinite(s.mean_clearance_m)) {
        std::snprintf(clearance, sizeof clearance, ", mean clearance %.3f mm",
                      s.mean_clearance_m * 1e3);
      }
      std::printf("score %s: %.1f%s (contact/fault %.2f s in %u episodes%s, tremor %.1f um)\n",
                  v.info.header.station_id.c_str(), s.score, s.is_final ? " final" : "",
                  s.time_in_contact_s, s.contacts, clearance, s.tremor_rms_m * 1e6);
    }
    if (const std::string rej = instructor::FormatRejected(console.Rejected()); !rej.empty()) {
      std::printf("%s\n", rej.c_str());
    }
    for (const auto& g : console.InputGaps()) {
      std::printf("input gap %s: steps %llu..%llu missing\n", g.station_id.c_str(),
                  static_cast<unsigned long long>(g.first_missing_step),
                  static_cast<unsigned long long>(g.last_missing_step));
    }
    web.reset();      // no more page commands
    session.reset();  // a replay playing stops
    if (const std::string recording = console.RecordingPath(); !recording.empty()) {
      const auto r = *console.StopRecording();
      std::printf("recorded %llu samples to %s (%llu dropped%s%s)\n",
                  static_cast<unsigned long long>(r.written), recording.c_str(),
                  static_cast<unsigned long long>(r.dropped),
                  r.error.empty() ? "" : "; error: ", r.error.c_str());
      if (!r.error.empty()) {
        std::fflush(stdout);
        std::fprintf(stderr, "microdex-instructor: %s\n", r.error.c_str());
        return 2;
      }
    }
    std::fflush(stdout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-instructor: %s\n", e.what());
    return 2;
  }
  return 0;
}
