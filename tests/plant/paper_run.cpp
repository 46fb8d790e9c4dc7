#include "tests/plant/paper_run.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace rig::plant::calib {

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The profile of one run: the built-in base with this run's seed and overrides.
std::string profile_text(const RunSpec& s) {
  toml::table plant{{"seed", static_cast<int64_t>(s.seed)}};
  if (s.dut) plant.insert("dut", *s.dut);
  toml::table t{{"base", s.base}, {"plant", plant}};
  if (!s.taus.empty()) t.insert("analysis", toml::table{{"taus", s.taus}});
  std::ostringstream o;
  o << t << "\n";
  return o.str();
}

int spawn_and_wait(std::vector<std::string> args, const fs::path& out, const fs::path& err) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error(args[0] + ": cannot start: " + std::strerror(rc));
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

}  // namespace

std::optional<double> PaperRun::value(const std::string& name) const {
  const auto& v = passport.at("values").at(name).at("value");
  if (v.is_null()) return std::nullopt;
  return v.get<double>();
}

PaperRun run_rig(const std::string& rig_binary, const RunSpec& spec) {
  static std::atomic<int> serial{0};
  const fs::path dir = fs::temp_directory_path() / ("rig-calib-" + std::to_string(::getpid()) + "-" +
                                                    std::to_string(spec.seed) + "-" + std::to_string(serial++));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "profile.toml") << profile_text(spec);
  const int rc = spawn_and_wait({rig_binary, "run", "--plant", "emulated", "--profile", (dir / "profile.toml").string(),
                                 "--yes", "--quiet", "--no-history", "--out", (dir / "run").string()},
                                dir / "stdout", dir / "stderr");
  PaperRun r;
  r.seed = spec.seed;
  try {
    if (rc != 0 && rc != 1)
      throw std::runtime_error("rig run (seed " + std::to_string(spec.seed) + ") exited " + std::to_string(rc) + ": " +
                               slurp(dir / "stderr"));
    r.passport = nlohmann::json::parse(slurp(dir / "run" / "passport.json"));
    r.analysis = nlohmann::json::parse(slurp(dir / "run" / "analysis.json"));
  } catch (...) {
    fs::remove_all(dir);
    throw;
  }
  fs::remove_all(dir);
  return r;
}

std::vector<PaperRun> run_seeds(const std::string& rig_binary, RunSpec spec, const std::vector<uint64_t>& seeds,
                                int parallel) {
  std::vector<PaperRun> out(seeds.size());
  const auto step = static_cast<std::size_t>(std::max(1, parallel));
  for (std::size_t i = 0; i < seeds.size(); i += step) {
    std::vector<std::future<PaperRun>> f;
    for (std::size_t j = i; j < std::min(seeds.size(), i + step); ++j) {
      RunSpec s = spec;
      s.seed = seeds[j];
      f.push_back(std::async(std::launch::async, [&rig_binary, s] { return run_rig(rig_binary, s); }));
    }
    for (std::size_t j = 0; j < f.size(); ++j) out[i + j] = f[j].get();
  }
  return out;
}

}  // namespace rig::plant::calib
