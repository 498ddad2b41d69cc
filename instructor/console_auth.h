#pragma once
// Instructor login for the console over HTTPS (`microdex-instructor --security DIR` or
// `--users FILE`; instructor/README.md "Security"):
// - users: a text file, one "NAME:ROLE:HASH" a line, HASH an Argon2id string of libsodium's
//   crypto_pwhash_str (salted, 64 MiB, a fresh salt per user); ROLE instructor (watches and
//   sends cues) or observer (watches only). `microdex-instructor --add-user NAME` writes it.
// - sessions: a random 256-bit token in a cookie (HttpOnly, Secure, SameSite=Strict) that
//   expires after an idle time and at the latest kSessionLifetime_ns after login.
// - the gate (view_server.h): without a valid session only the login form is served; a
//   WebSocket upgrade needs a valid session and an Origin equal to https://HOST of the
//   request; cue commands need the instructor role, checked per message.
//
// Threads: everything runs on the view server's thread, except AddUser (main, before).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/view/view_server.h"

namespace microdex::instructor {

enum class Role { kInstructor, kObserver };
const char* RoleName(Role r);
// Throws std::invalid_argument naming the text when it is neither role.
Role ParseRole(const std::string& text);

struct ConsoleUser {
  std::string name;
  Role role = Role::kInstructor;
  std::string hash;  // crypto_pwhash_str
};

// Reads the users file; throws std::runtime_error naming the file and line of a bad entry.
std::vector<ConsoleUser> LoadUsers(const std::string& path);
// Adds (or replaces) `name` with the hash of `password` and rewrites the file (mode 0600).
// Throws std::invalid_argument for a bad name or a password under kMinPasswordLength,
// std::runtime_error when the file cannot be written.
void AddUser(const std::string& path, const std::string& name, Role role,
             const std::string& password);
inline constexpr std::size_t kMinPasswordLength = 10;

struct ConsoleSession {
  std::string user;
  Role role = Role::kInstructor;
  std::int64_t created_ns = 0, last_seen_ns = 0;  // monotonic
};

class ConsoleAuth {
 public:
  static constexpr std::int64_t kSessionLifetime_ns = 12LL * 3600 * 1'000'000'000;
  static constexpr const char* kCookie = "microdex_session";

  // users: from LoadUsers (at least one); idle_timeout_s: a session unused this long ends.
  ConsoleAuth(std::vector<ConsoleUser> users, double idle_timeout_s);

  // The view server's gate at monotonic time now_ns (view::ViewServer::GateFn).
  std::optional<view::HttpReply> Gate(const view::HttpRequestInfo& request, std::string* client,
                                      std::int64_t now_ns);
  // The session of a token if it is still valid at now_ns (and marks it used).
  std::optional<ConsoleSession> Session(const std::string& token, std::int64_t now_ns);

  // Checks name and password (slow by design: one Argon2id verification); a session token
  // or nullopt. Failed attempts are throttled: one per kFailedLoginDelay_ns.
  std::optional<std::string> LogIn(const std::string& name, const std::string& password,
                                   std::int64_t now_ns);
  static constexpr std::int64_t kFailedLoginDelay_ns = 1'000'000'000;

  std::size_t sessions() const { return sessions_.size(); }

 private:
  std::string TokenOf(const std::string& cookie_header) const;
  void Expire(std::int64_t now_ns);

  std::vector<ConsoleUser> users_;
  std::int64_t idle_timeout_ns_;
  std::map<std::string, ConsoleSession> sessions_;  // by token
  std::int64_t next_attempt_ns_ = 0;
};

}  // namespace microdex::instructor
