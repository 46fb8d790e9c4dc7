// Shared fixtures for the table tests: emulator set-ups that move fast in real
// time, child processes (socat, a server to kill), free ports.
#pragma once
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "plant/table/table_emulator.hpp"
#include "rig/core/toml_util.hpp"

extern char** environ;

namespace rig::table_test {

using plant::SimFault;

// A table that turns 180° in about 0.6 s of real time and homes in ~0.1 s.
inline const char* kFastTable = R"(
velocity_dps = 360.0
accel_dps2 = 1800.0
home_velocity_dps = 200.0
settle_s = 0.05
start_angle_deg = 10.0
)";

inline std::unique_ptr<plant::TableEmulator> emulator(const std::string& toml_text, uint64_t seed = 7) {
  const toml::table t = cfg::parse_string(toml_text, "test-table.toml");
  return plant::make_table_emulator(&t, seed);
}

// A child process; killed (SIGKILL) and reaped on destruction.
class Child {
 public:
  explicit Child(const std::vector<std::string>& argv, int* stdout_fd = nullptr) {
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    int pipefd[2] = {-1, -1};
    if (stdout_fd) {
      if (pipe(pipefd) != 0) throw std::runtime_error("pipe failed");
      posix_spawn_file_actions_adddup2(&fa, pipefd[1], 1);
      posix_spawn_file_actions_addclose(&fa, pipefd[0]);
    }
    const int rc = posix_spawn(&pid_, argv[0].c_str(), &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (stdout_fd) {
      close(pipefd[1]);
      *stdout_fd = pipefd[0];
    }
    if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  }
  ~Child() { kill_now(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  void kill_now() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    int st = 0;
    waitpid(pid_, &st, 0);
    pid_ = -1;
  }
  pid_t pid() const { return pid_; }
  // Waits for the child to exit; its wait status.
  int wait_status() {
    int st = 0;
    waitpid(pid_, &st, 0);
    pid_ = -1;
    return st;
  }

 private:
  pid_t pid_ = -1;
};

// Reads one line from fd (blocking, bounded by the child writing it).
inline std::string read_line(int fd) {
  std::string s;
  char c;
  while (::read(fd, &c, 1) == 1 && c != '\n') s += c;
  return s;
}

// Runs a command, returns its exit status and combined output.
inline int run(const std::string& cmd, std::string& out) {
  out.clear();
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[512];
  while (fgets(buf, sizeof buf, p)) out += buf;
  const int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// A socat pseudo-terminal pair (the RTU "cable"), removed on destruction.
class PtyPair {
 public:
  PtyPair() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "rig-table-pty-XXXXXX").string();
    if (mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp for the pty pair failed");
    dir_ = tmpl;
    a_ = dir_ + "/a";
    b_ = dir_ + "/b";
    plug();
  }
  ~PtyPair() {
    socat_.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  // The cable pulled: socat killed, its links removed (a killed socat leaves them).
  void unplug() {
    socat_.reset();
    std::filesystem::remove(a_);
    std::filesystem::remove(b_);
  }
  // A new pair under the same link names (a USB adapter plugged back in).
  void plug() {
    socat_ = std::make_unique<Child>(std::vector<std::string>{
        "/usr/bin/socat", "pty,raw,echo=0,link=" + a_, "pty,raw,echo=0,link=" + b_});
    for (int i = 0; i < 500 && !(std::filesystem::exists(a_) && std::filesystem::exists(b_)); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (!std::filesystem::exists(a_) || !std::filesystem::exists(b_)) throw std::runtime_error("socat pty pair did not appear");
  }
  const std::string& a() const { return a_; }
  const std::string& b() const { return b_; }

 private:
  std::string dir_, a_, b_;
  std::unique_ptr<Child> socat_;
};

// The message a call fails with, or "(no error)".
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}
inline bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace rig::table_test
