// `rig` as a child process for the process-level tests (test_rig_cli, test_campaigns): spawn
// with its stdio in files and a private history database, wait for its exit code, read files.
#pragma once
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

extern char** environ;

namespace rig::test {

struct Child {
  pid_t pid = -1;
  std::string out, err;
};

// A fresh temporary folder name for this test process.
inline std::string tmp(const std::string& name) {
  const std::string d =
      std::filesystem::temp_directory_path() / ("rigcli-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(d);
  return d;
}

// A station key (32 bytes, owner-only, as `rig run --seal-key` takes one) at dir/station.key,
// the folder made; its path.
inline std::string station_key_in(const std::string& dir) {
  namespace fs = std::filesystem;
  const std::string key = dir + "/station.key";
  fs::create_directories(dir);
  std::ofstream(key, std::ios::binary) << std::string(32, 'k');
  fs::permissions(key, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  return key;
}

inline std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Starts RIG_BINARY with `args`; stdout and stderr go to io_prefix.stdout / .stderr, the
// history to io_prefix.history.sqlite (tests never touch the user's database); stdin reads `in`.
// err_fd >= 0: stderr is that descriptor instead (a pipe, say).
inline Child spawn(const std::vector<std::string>& args, const std::string& io_prefix,
                   const std::string& in = "/dev/null", int err_fd = -1) {
  std::vector<char*> argv;
  std::string bin = RIG_BINARY;
  argv.push_back(bin.data());
  std::vector<std::string> copy = args;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  Child c;
  c.out = io_prefix + ".stdout";
  c.err = io_prefix + ".stderr";
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, in.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, c.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (err_fd >= 0) posix_spawn_file_actions_adddup2(&fa, err_fd, 2);
  else posix_spawn_file_actions_addopen(&fa, 2, c.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const std::string hist = "RIG_HISTORY=sqlite:" + io_prefix + ".history.sqlite";
  std::vector<char*> envp;
  for (char** e = environ; *e; ++e)
    if (std::string(*e).rfind("RIG_HISTORY=", 0) != 0) envp.push_back(*e);
  std::string h = hist;
  envp.push_back(h.data());
  envp.push_back(nullptr);
  EXPECT_EQ(posix_spawn(&c.pid, bin.c_str(), &fa, nullptr, argv.data(), envp.data()), 0);
  posix_spawn_file_actions_destroy(&fa);
  return c;
}

// The exit code, or 128 + the signal that ended it.
inline int wait_exit(const Child& c) {
  int st = 0;
  ::waitpid(c.pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

inline int run(const std::vector<std::string>& args, const std::string& io_prefix,
               const std::string& in = "/dev/null") {
  return wait_exit(spawn(args, io_prefix, in));
}

// Polls (bounded) until `path` exists; returns false if the child ended first.
inline bool wait_for_file(const Child& c, const std::string& path) {
  for (int i = 0; i < 60000; ++i) {
    if (std::filesystem::exists(path)) return true;
    int st;
    if (::waitpid(c.pid, &st, WNOHANG) == c.pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

inline std::size_t count(const std::string& hay, const std::string& needle) {
  std::size_t n = 0;
  for (auto p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + 1)) ++n;
  return n;
}

}  // namespace rig::test
