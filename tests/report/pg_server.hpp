// A throw-away PostgreSQL server for the tests: initdb into a temp folder, started with
// pg_ctl, listening only on a unix socket inside that folder (listen_addresses = ''), so
// no TCP port can clash with anything else on the machine. PostgreSQL refuses to run as
// root, so under root (CI) the server runs as `nobody`. Stopped and deleted on destruction.
#pragma once
#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/report/fixture.hpp"

namespace rig::test {

class PgServer {
 public:
  // The folder holding initdb/pg_ctl, or "" if PostgreSQL is not installed.
  static std::string bin_dir() {
    if (const char* e = std::getenv("RIG_PG_BIN"); e && *e) return e;
    for (int v = 20; v >= 11; --v) {
      const std::string d = "/usr/lib/postgresql/" + std::to_string(v) + "/bin";
      if (std::filesystem::exists(d + "/pg_ctl")) return d;
    }
    return "";
  }

  PgServer() : bin_(bin_dir()) {
    if (bin_.empty()) return;
    const std::string data = (dir_.path / "data").string();
    if (geteuid() == 0) {
      const passwd* pw = getpwnam("nobody");
      if (!pw) throw std::runtime_error("no user 'nobody' to run PostgreSQL as");
      uid_ = pw->pw_uid;
      gid_ = pw->pw_gid;
      if (chown(dir_.path.c_str(), uid_, gid_) != 0) throw std::runtime_error("chown of the temp folder failed");
    }
    must({bin_ + "/initdb", "-D", data, "-A", "trust", "-U", "rig", "-E", "UTF8", "--locale=C", "--no-sync"}, "initdb");
    must({bin_ + "/pg_ctl", "-D", data, "-l", (dir_.path / "server.log").string(), "-w", "-t", "60", "-o",
          "-k " + dir_.path.string() + " -c listen_addresses='' -p " + std::to_string(kPort) +
              " -c fsync=off -c full_page_writes=off",
          "start"},
         "pg_ctl start");
    running_ = true;
  }
  ~PgServer() {
    if (running_) run({bin_ + "/pg_ctl", "-D", (dir_.path / "data").string(), "-m", "fast", "-w", "stop"});
  }
  PgServer(const PgServer&) = delete;
  PgServer& operator=(const PgServer&) = delete;

  bool available() const { return running_; }
  // A libpq URL for database `db` on this server.
  std::string url(const std::string& db = "postgres") const {
    return "postgresql://rig@/" + db + "?host=" + dir_.path.string() + "&port=" + std::to_string(kPort);
  }
  // Runs SQL through psql (as the test's own client, independent of the code under test).
  void psql(const std::string& db, const std::string& sql) {
    must({bin_ + "/psql", "-X", "-q", "-v", "ON_ERROR_STOP=1", "-h", dir_.path.string(), "-p", std::to_string(kPort),
          "-U", "rig", "-d", db, "-c", sql},
         "psql");
  }
  std::string log() const {
    std::ifstream in(dir_.path / "server.log");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

 private:
  static constexpr int kPort = 54329;

  // fork + exec (no shell, no quoting), as the server's user when running as root;
  // stdout/stderr appended to the folder's tool.log.
  int run(const std::vector<std::string>& argv) {
    const std::string logf = (dir_.path / "tool.log").string();
    const pid_t pid = fork();
    if (pid == 0) {
      const int fd = open(logf.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
      }
      if (uid_ != 0 && geteuid() == 0) {
        if (setgroups(0, nullptr) != 0 || setgid(gid_) != 0 || setuid(uid_) != 0) _exit(126);
      }
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) < 0) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  void must(const std::vector<std::string>& argv, const char* what) {
    if (run(argv) != 0) {
      std::ifstream in(dir_.path / "tool.log");
      std::ostringstream ss;
      ss << in.rdbuf();
      throw std::runtime_error(std::string(what) + " failed:\n" + ss.str());
    }
  }

  TempDir dir_;
  std::string bin_;
  uid_t uid_ = 0;
  gid_t gid_ = 0;
  bool running_ = false;
};

}  // namespace rig::test
