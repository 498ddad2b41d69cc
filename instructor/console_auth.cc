#include "instructor/console_auth.h"

#include <sodium.h>
#include <sys/stat.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace microdex::instructor {
namespace {

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char ch : name) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                    (ch >= '0' && ch <= '9') || ch == '.' || ch == '_' || ch == '-';
    if (!ok) return false;
  }
  return true;
}

void InitSodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium: cannot initialise");
}

// application/x-www-form-urlencoded value of `key` in `body` ("" when absent).
std::string FormValue(const std::string& body, const std::string& key) {
  std::size_t at = 0;
  while (at <= body.size()) {
    std::size_t end = body.find('&', at);
    if (end == std::string::npos) end = body.size();
    const std::string pair = body.substr(at, end - at);
    if (pair.starts_with(key + "=")) {
      std::string out;
      const std::string v = pair.substr(key.size() + 1);
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (v[i] == '+') {
          out += ' ';
        } else if (v[i] == '%' && i + 2 < v.size() &&
                   std::isxdigit(static_cast<unsigned char>(v[i + 1])) &&
                   std::isxdigit(static_cast<unsigned char>(v[i + 2]))) {
          out += static_cast<char>(std::stoi(v.substr(i + 1, 2), nullptr, 16));
          i += 2;
        } else {
          out += v[i];
        }
      }
      return out;
    }
    at = end + 1;
  }
  return {};
}

std::string LoginPage(const std::string& message) {
  return R"(<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>microdex console: log in</title>
<style>body{font:16px system-ui,sans-serif;background:#15181c;color:#dde;display:grid;place-items:center;height:100vh;margin:0}
form{display:grid;gap:.6em;background:#22262c;padding:2em;border-radius:8px;min-width:18em}
input,button{font:inherit;padding:.4em}p.error{color:#f88;margin:0}</style></head>
<body><form method="post" action="/login"><h1>microdex console</h1>)" +
         (message.empty() ? std::string() : "<p class=\"error\" id=\"error\">" + message + "</p>") +
         R"(<label>User <input name="user" id="user" autocomplete="username" required></label>
<label>Password <input name="password" id="password" type="password" autocomplete="current-password" required></label>
<button type="submit" id="login">Log in</button></form></body></html>
)";
}

view::HttpReply Html(unsigned status, std::string body) {
  view::HttpReply r;
  r.status = status;
  r.content_type = "text/html; charset=utf-8";
  r.body = std::move(body);
  return r;
}

view::HttpReply Text(unsigned status, std::string body) {
  view::HttpReply r;
  r.status = status;
  r.body = std::move(body);
  return r;
}

view::HttpReply Redirect(const std::string& to) {
  view::HttpReply r;
  r.status = 303;
  r.headers.emplace_back("Location", to);
  return r;
}

}  // namespace

const char* RoleName(Role r) { return r == Role::kInstructor ? "instructor" : "observer"; }

Role ParseRole(const std::string& text) {
  if (text == "instructor") return Role::kInstructor;
  if (text == "observer") return Role::kObserver;
  throw std::invalid_argument("role '" + text.substr(0, 32) + "': expected instructor|observer");
}

std::vector<ConsoleUser> LoadUsers(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("users file '" + path +
                             "': cannot read it (add a user with microdex-instructor --add-user "
                             "NAME)");
  }
  std::vector<ConsoleUser> users;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    const std::size_t a = line.find(':');
    const std::size_t b = a == std::string::npos ? a : line.find(':', a + 1);
    const auto bad = [&](const std::string& why) {
      std::string message = "users file '" + path + "' line " + std::to_string(n) + ": ";
      message += why;
      return std::runtime_error(message);
    };
    if (b == std::string::npos) throw bad("expected NAME:ROLE:HASH");
    ConsoleUser u;
    u.name = line.substr(0, a);
    if (!ValidName(u.name)) throw bad("bad user name");
    try {
      u.role = ParseRole(line.substr(a + 1, b - a - 1));
    } catch (const std::invalid_argument& e) {
      throw bad(e.what());
    }
    u.hash = line.substr(b + 1);
    if (!u.hash.starts_with("$argon2id$") || u.hash.size() >= crypto_pwhash_STRBYTES) {
      throw bad("expected an Argon2id hash ($argon2id$...)");
    }
    users.push_back(std::move(u));
  }
  return users;
}

void AddUser(const std::string& path, const std::string& name, Role role,
             const std::string& password) {
  InitSodium();
  if (!ValidName(name)) {
    throw std::invalid_argument("user name '" + name.substr(0, 64) +
                                "': expected 1..64 of A-Z a-z 0-9 . _ -");
  }
  if (password.size() < kMinPasswordLength) {
    throw std::invalid_argument("password: at least " + std::to_string(kMinPasswordLength) +
                                " characters");
  }
  std::vector<ConsoleUser> users;
  if (std::filesystem::exists(path)) users = LoadUsers(path);
  std::erase_if(users, [&](const ConsoleUser& u) { return u.name == name; });
  char hash[crypto_pwhash_STRBYTES];
  if (crypto_pwhash_str(hash, password.c_str(), password.size(), crypto_pwhash_OPSLIMIT_INTERACTIVE,
                        crypto_pwhash_MEMLIMIT_INTERACTIVE) != 0) {
    throw std::runtime_error("password hash: out of memory");
  }
  users.push_back({name, role, hash});
  const std::string tmp = path + ".new";
  {
    const mode_t old = umask(077);
    std::ofstream out(tmp, std::ios::trunc);
    umask(old);
    if (!out) throw std::runtime_error("users file '" + tmp + "': cannot write it");
    out << "# microdex console users: NAME:ROLE:ARGON2ID-HASH (microdex-instructor --add-user)\n";
    for (const ConsoleUser& u : users)
      out << u.name << ':' << RoleName(u.role) << ':' << u.hash << '\n';
    if (!out.flush()) throw std::runtime_error("users file '" + tmp + "': cannot write it");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("users file '" + path + "': " + ec.message());
}

ConsoleAuth::ConsoleAuth(std::vector<ConsoleUser> users, double idle_timeout_s)
    : users_(std::move(users)), idle_timeout_ns_(static_cast<std::int64_t>(idle_timeout_s * 1e9)) {
  InitSodium();
  if (users_.empty()) {
    throw std::runtime_error("console login: no users (microdex-instructor --add-user NAME)");
  }
  if (!(idle_timeout_s > 0)) throw std::invalid_argument("session timeout: expected > 0 s");
}

void ConsoleAuth::Expire(std::int64_t now_ns) {
  std::erase_if(sessions_, [&](const auto& kv) {
    const ConsoleSession& s = kv.second;
    return now_ns - s.last_seen_ns > idle_timeout_ns_ ||
           now_ns - s.created_ns > kSessionLifetime_ns;
  });
}

std::optional<ConsoleSession> ConsoleAuth::Session(const std::string& token, std::int64_t now_ns) {
  Expire(now_ns);
  const auto it = sessions_.find(token);
  if (token.empty() || it == sessions_.end()) return std::nullopt;
  it->second.last_seen_ns = now_ns;
  return it->second;
}

std::optional<std::string> ConsoleAuth::LogIn(const std::string& name, const std::string& password,
                                              std::int64_t now_ns) {
  if (now_ns < next_attempt_ns_) return std::nullopt;
  const ConsoleUser* user = nullptr;
  for (const ConsoleUser& u : users_) {
    if (u.name == name) user = &u;
  }
  // An unknown name costs the same verification as a known one.
  const std::string& hash = user != nullptr ? user->hash : users_.front().hash;
  const bool ok = crypto_pwhash_str_verify(hash.c_str(), password.c_str(), password.size()) == 0;
  if (!ok || user == nullptr) {
    next_attempt_ns_ = now_ns + kFailedLoginDelay_ns;
    return std::nullopt;
  }
  unsigned char raw[32];
  randombytes_buf(raw, sizeof raw);
  char hex[2 * sizeof raw + 1];
  sodium_bin2hex(hex, sizeof hex, raw, sizeof raw);
  Expire(now_ns);
  sessions_[hex] = {user->name, user->role, now_ns, now_ns};
  return std::string(hex);
}

std::string ConsoleAuth::TokenOf(const std::string& cookie_header) const {
  const std::string key = std::string(kCookie) + "=";
  std::size_t at = 0;
  while ((at = cookie_header.find(key, at)) != std::string::npos) {
    if (at == 0 || cookie_header[at - 1] == ' ' || cookie_header[at - 1] == ';') {
      const std::size_t start = at + key.size();
      const std::size_t end = cookie_header.find(';', start);
      return cookie_header.substr(start, end == std::string::npos ? end : end - start);
    }
    at += key.size();
  }
  return {};
}

std::optional<view::HttpReply> ConsoleAuth::Gate(const view::HttpRequestInfo& request,
                                                 std::string* client, std::int64_t now_ns) {
  if (request.target == "/login" && !request.websocket) {
    if (request.method == "GET" || request.method == "HEAD") return Html(200, LoginPage(""));
    if (request.method != "POST") return Text(405, "GET or POST\n");
    if (now_ns < next_attempt_ns_) {
      return Html(429, LoginPage("Too many attempts: wait a second and try again."));
    }
    const std::optional<std::string> token =
        LogIn(FormValue(request.body, "user"), FormValue(request.body, "password"), now_ns);
    if (!token) return Html(401, LoginPage("Wrong user or password."));
    view::HttpReply r = Redirect("/");
    r.headers.emplace_back("Set-Cookie", std::string(kCookie) + "=" + *token +
                                             "; Path=/; HttpOnly; Secure; SameSite=Strict; "
                                             "Max-Age=" +
                                             std::to_string(kSessionLifetime_ns / 1'000'000'000));
    return r;
  }
  const std::string token = TokenOf(request.cookie);
  if (request.target == "/logout" && request.method == "POST") {
    sessions_.erase(token);
    view::HttpReply r = Redirect("/login");
    r.headers.emplace_back("Set-Cookie", std::string(kCookie) +
                                             "=; Path=/; HttpOnly; Secure; SameSite=Strict; "
                                             "Max-Age=0");
    return r;
  }
  if (!Session(token, now_ns)) {
    if (!request.websocket && (request.target == "/" || request.target == "/console.html")) {
      return Redirect("/login");
    }
    return Text(401, "log in first (/login)\n");
  }
  if (request.websocket && request.origin != "https://" + request.host) {
    return Text(403,
                "WebSocket origin '" + request.origin.substr(0, 128) + "' is not this console's\n");
  }
  *client = token;
  return std::nullopt;
}

}  // namespace microdex::instructor
