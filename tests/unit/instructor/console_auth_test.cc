// Console login (instructor/console_auth.h): the users file (Argon2id, salted, refused when
// malformed), passwords checked, failed attempts throttled, sessions that end when idle and at
// their lifetime, the gate's answers (login form, redirect, 401, origin check), cookie flags.
// Time is injected (monotonic ns), never read.
#include "instructor/console_auth.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

namespace microdex::instructor {
namespace {

constexpr std::int64_t kSecond_ns = 1'000'000'000;

class ConsoleAuthTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = ::testing::TempDir() + "/console_users_" + std::to_string(getpid());
    std::filesystem::remove(path_);
    AddUser(path_, "ada", Role::kInstructor, "ada's long password");
    AddUser(path_, "obs", Role::kObserver, "ada's long password");  // the same password
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::string path_;
};

view::HttpRequestInfo Request(const std::string& method, const std::string& target,
                              const std::string& cookie = "", const std::string& body = "") {
  view::HttpRequestInfo r;
  r.method = method;
  r.target = target;
  r.cookie = cookie;
  r.body = body;
  r.host = "console.example:8443";
  return r;
}

std::string Header(const view::HttpReply& r, const std::string& name) {
  for (const auto& [n, v] : r.headers) {
    if (n == name) return v;
  }
  return {};
}

TEST_F(ConsoleAuthTest, UsersFileHoldsSaltedArgon2idHashesOnly) {
  const std::vector<ConsoleUser> users = LoadUsers(path_);
  ASSERT_EQ(users.size(), 2u);
  EXPECT_EQ(users[0].role, Role::kInstructor);
  EXPECT_EQ(users[1].role, Role::kObserver);
  for (const ConsoleUser& u : users) {
    EXPECT_TRUE(u.hash.starts_with("$argon2id$")) << u.hash;
    EXPECT_EQ(u.hash.find("long password"), std::string::npos);
  }
  EXPECT_NE(users[0].hash, users[1].hash) << "same password, same hash: no salt";
  struct stat st {};
  ASSERT_EQ(stat(path_.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 077, 0u) << "the users file is readable by others";
  // Replacing a user keeps one entry.
  AddUser(path_, "ada", Role::kObserver, "another long password");
  EXPECT_EQ(LoadUsers(path_).size(), 2u);
}

TEST_F(ConsoleAuthTest, BadUsersAndPasswordsAreRefusedByName) {
  EXPECT_THROW(AddUser(path_, "ada", Role::kInstructor, "short"), std::invalid_argument);
  EXPECT_THROW(AddUser(path_, "a:b", Role::kInstructor, "long enough pw"), std::invalid_argument);
  EXPECT_THROW(ParseRole("admin"), std::invalid_argument);
  const std::string bad = path_ + ".bad";
  std::ofstream(bad) << "ada:instructor:$argon2id$v=19$m=65536,t=2,p=1$x$y\nbob:root:$argon2id$\n";
  try {
    LoadUsers(bad);
    ADD_FAILURE() << "a bad role was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  std::ofstream(bad) << "ada:instructor:plaintext\n";
  EXPECT_THROW(LoadUsers(bad), std::runtime_error);
  std::filesystem::remove(bad);
  EXPECT_THROW(ConsoleAuth({}, 60), std::runtime_error);
}

TEST_F(ConsoleAuthTest, LoginChecksThePasswordAndThrottlesFailures) {
  ConsoleAuth auth(LoadUsers(path_), 600);
  std::int64_t t = 100 * kSecond_ns;
  EXPECT_FALSE(auth.LogIn("ada", "wrong password", t));
  // Within the delay even the right password is not checked.
  EXPECT_FALSE(auth.LogIn("ada", "ada's long password", t + kSecond_ns / 2));
  t += 2 * kSecond_ns;
  EXPECT_FALSE(auth.LogIn("nobody", "ada's long password", t));
  t += 2 * kSecond_ns;
  const std::optional<std::string> token = auth.LogIn("ada", "ada's long password", t);
  ASSERT_TRUE(token);
  EXPECT_EQ(token->size(), 64u);  // 256 bits, hex
  const std::optional<std::string> other = auth.LogIn("obs", "ada's long password", t);
  ASSERT_TRUE(other);
  EXPECT_NE(*token, *other);
  EXPECT_EQ(auth.Session(*token, t)->role, Role::kInstructor);
  EXPECT_EQ(auth.Session(*other, t)->role, Role::kObserver);
}

TEST_F(ConsoleAuthTest, SessionsEndWhenIdleAndAtTheirLifetime) {
  ConsoleAuth auth(LoadUsers(path_), 60);
  std::int64_t t = 10 * kSecond_ns;
  const std::string token = *auth.LogIn("ada", "ada's long password", t);
  // Used every 50 s: stays open past the idle timeout...
  for (int i = 0; i < 10; ++i) {
    t += 50 * kSecond_ns;
    ASSERT_TRUE(auth.Session(token, t)) << "at " << i;
  }
  // ...and ends after 61 s unused.
  t += 61 * kSecond_ns;
  EXPECT_FALSE(auth.Session(token, t));
  EXPECT_EQ(auth.sessions(), 0u);
  // A session in use all the time ends at its lifetime anyway.
  ConsoleAuth busy(LoadUsers(path_), 3600);
  t = kSecond_ns;
  const std::string token2 = *busy.LogIn("ada", "ada's long password", t);
  for (; t < ConsoleAuth::kSessionLifetime_ns; t += 1800 * kSecond_ns) {
    ASSERT_TRUE(busy.Session(token2, t));
  }
  EXPECT_FALSE(busy.Session(token2, t + kSecond_ns));
}

TEST_F(ConsoleAuthTest, TheGateServesOnlyTheLoginFormWithoutASession) {
  ConsoleAuth auth(LoadUsers(path_), 600);
  const std::int64_t t = 5 * kSecond_ns;
  std::string client;
  auto r = auth.Gate(Request("GET", "/"), &client, t);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 303u);
  EXPECT_EQ(Header(*r, "Location"), "/login");
  for (const char* target : {"/console.js", "/scene/s1.json", "/frame_worker.js"}) {
    r = auth.Gate(Request("GET", target), &client, t);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 401u) << target;
  }
  view::HttpRequestInfo ws = Request("GET", "/ws");
  ws.websocket = true;
  ws.origin = "https://console.example:8443";
  r = auth.Gate(ws, &client, t);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 401u);
  r = auth.Gate(Request("GET", "/login"), &client, t);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200u);
  EXPECT_NE(r->body.find("<form method=\"post\" action=\"/login\">"), std::string::npos);

  // Logging in: a cookie with every flag, then the pages go through.
  r = auth.Gate(Request("POST", "/login", "", "user=ada&password=ada%27s+long+password"), &client,
                t);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 303u);
  const std::string set_cookie = Header(*r, "Set-Cookie");
  for (const char* flag : {"; HttpOnly", "; Secure", "; SameSite=Strict", "; Path=/"}) {
    EXPECT_NE(set_cookie.find(flag), std::string::npos) << set_cookie;
  }
  const std::string cookie = "theme=dark; " + set_cookie.substr(0, set_cookie.find(';'));
  EXPECT_FALSE(auth.Gate(Request("GET", "/console.js", cookie), &client, t));
  // The WebSocket: the session and the console's own origin.
  ws.cookie = cookie;
  client.clear();
  EXPECT_FALSE(auth.Gate(ws, &client, t));
  EXPECT_EQ(client, set_cookie.substr(17, 64));  // the token names the client
  ws.origin = "https://evil.example";
  r = auth.Gate(ws, &client, t);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 403u);
  ws.origin = "";
  EXPECT_EQ(auth.Gate(ws, &client, t)->status, 403u);
  // A made-up token is no session.
  EXPECT_EQ(auth.Gate(Request("GET", "/console.js", "microdex_session=" + std::string(64, 'a')),
                      &client, t)
                ->status,
            401u);
  // Logging out ends it.
  auth.Gate(Request("POST", "/logout", cookie), &client, t);
  EXPECT_EQ(auth.Gate(Request("GET", "/console.js", cookie), &client, t)->status, 401u);
}

}  // namespace
}  // namespace microdex::instructor
