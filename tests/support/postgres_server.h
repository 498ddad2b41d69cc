#pragma once
// A real PostgreSQL server for the tests, started in a temporary folder on a free loopback
// port (initdb -A trust, pg_ctl; as `nobody` through runuser when the test runs as root) and
// stopped after the test. Skipped, saying why, when Debian's postgresql binaries are missing.

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "common/scores/scores_db.h"

namespace microdex::testing {

inline constexpr const char* kPgBin = "/usr/lib/postgresql/15/bin";

inline int FreeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) {
    port = ntohs(a.sin_port);
  }
  close(fd);
  return port;
}

// initdb + pg_ctl in a temporary folder, listening on 127.0.0.1 only, trust authentication.
// PostgreSQL refuses to run as root: as root the server runs as `nobody`.
class PostgresServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string initdb = std::string(kPgBin) + "/initdb";
    if (access(initdb.c_str(), X_OK) != 0) {
      GTEST_SKIP() << initdb << " not found (Debian package postgresql; deploy/install-deps)";
    }
    dir_ = "/tmp/microdex-pg-XXXXXX";
    ASSERT_NE(mkdtemp(dir_.data()), nullptr);
    port_ = FreeLoopbackPort();
    ASSERT_GT(port_, 0);
    if (geteuid() == 0) {
      if (access("/usr/sbin/runuser", X_OK) != 0) {
        GTEST_SKIP() << "running as root and runuser is missing: cannot start PostgreSQL as "
                        "another user";
      }
      as_ = "runuser -u nobody -- ";
      user_ = "nobody";
      ASSERT_EQ(chmod(dir_.c_str(), 0777), 0);
    } else {
      const char* u = std::getenv("USER");
      user_ = u ? u : "postgres";
    }
    data_ = dir_ + "/data";
    ASSERT_EQ(Run(as_ + initdb + " -D " + data_ + " -A trust -U " + user_ +
                  " --no-sync -E UTF8 > " + dir_ + "/initdb.log 2>&1"),
              0)
        << Read(dir_ + "/initdb.log");
    const std::string opts = "-c listen_addresses=127.0.0.1 -c port=" + std::to_string(port_) +
                             " -c unix_socket_directories=" + dir_ + " -c fsync=off";
    ASSERT_EQ(Run(as_ + std::string(kPgBin) + "/pg_ctl -D " + data_ + " -o '" + opts + "' -l " +
                  dir_ + "/server.log -w -t 60 start > " + dir_ + "/pg_ctl.log 2>&1"),
              0)
        << Read(dir_ + "/pg_ctl.log") << Read(dir_ + "/server.log");
    started_ = true;
  }
  void TearDown() override {
    if (started_) {
      Run(as_ + std::string(kPgBin) + "/pg_ctl -D " + data_ +
          " -m immediate -w stop > /dev/null 2>&1");
    }
    if (!dir_.empty()) Run("rm -rf " + dir_);
  }
  static int Run(const std::string& cmd) { return std::system(cmd.c_str()); }
  static std::string Read(const std::string& path) {
    std::ifstream f(path);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }
  // A new database on the server, by its URL.
  std::string NewDatabase(const std::string& name) {
    const auto admin = scores::ScoresDb::Open(Url("postgres"), 0);
    admin->Exec("CREATE DATABASE " + name);
    return Url(name);
  }
  std::string Url(const std::string& db) const {
    return "postgresql://" + user_ + "@127.0.0.1:" + std::to_string(port_) + "/" + db;
  }

  std::string dir_, data_, as_, user_;
  int port_ = 0;
  bool started_ = false;
};

}  // namespace microdex::testing
