#include "rig/executive/executive.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rig/core/errors.hpp"

#include <spdlog/spdlog.h>

namespace rig {

const char* to_string(RunOutcome o) {
  switch (o) {
    case RunOutcome::Pass: return "PASS";
    case RunOutcome::Fail: return "FAIL";
    case RunOutcome::Aborted: return "ABORTED";
    case RunOutcome::Error: return "ERROR";
  }
  return "ERROR";
}

int RunResult::exit_code() const {
  switch (outcome) {
    case RunOutcome::Pass: return kExitPass;
    case RunOutcome::Fail: return kExitFail;
    case RunOutcome::Aborted: return kExitAborted;
    case RunOutcome::Error: return config_error ? kExitUsage : kExitHardware;
  }
  return kExitHardware;
}

void write_file_atomic(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + tmp);
  const char* p = content.data();
  std::size_t n = content.size();
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      ::close(fd);
      throw std::runtime_error("write failed: " + tmp);
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  ::fsync(fd);
  ::close(fd);
  std::filesystem::rename(tmp, path);
}

Executive::Executive(Devices& dev, std::string out_dir, std::shared_ptr<spdlog::logger> log, ProgressSink* progress)
    : dev_(dev), out_dir_(std::move(out_dir)), log_(std::move(log)), progress_(progress) {}

std::string Executive::checkpoint_path(const std::string& out_dir) { return out_dir + "/checkpoint.json"; }

void Executive::safe_state(Devices& dev, spdlog::logger& log, bool abnormal) {
  // Order matters: stop motion first (a turning table is the hazard), then
  // the stream, then power. Each step is independent of the others' failure.
  const auto lvl = abnormal ? spdlog::level::warn : spdlog::level::info;
  log.log(lvl, "safe state 1/3: stopping table ({})", dev.table.describe());
  dev.table.stop();
  log.log(lvl, "safe state 2/3: stopping DUT stream ({})", dev.dut.describe());
  dev.dut.stop_stream();
  log.log(lvl, "safe state 3/3: DUT power off ({})", dev.io.describe());
  try {
    dev.io.set_dut_power(false);
  } catch (const std::exception& e) {
    log.error("safe state: DUT power off failed: {}", e.what());
  }
  log.log(lvl, "safe state reached");
}

void Executive::write_checkpoint(const std::vector<std::string>& done, const MeasurementSet& values,
                                 const nlohmann::json& state, const nlohmann::json& identity) const {
  nlohmann::ordered_json j;
  j["schema"] = "rig.checkpoint/1";
  j["identity"] = identity;
  j["completed"] = done;
  j["values"] = values.to_json();
  j["state"] = state;
  write_file_atomic(checkpoint_path(out_dir_), j.dump(1));
}

RunResult Executive::run(const std::function<void(PhaseContext&)>& bring_up, const std::vector<Phase>& phases,
                         MeasurementSet& values, nlohmann::json& state, const CancelToken& cancel, bool resume,
                         const nlohmann::json& identity) {
  RunResult result;
  std::vector<std::string> done;
  if (resume) {
    const std::string cp = checkpoint_path(out_dir_);
    std::ifstream in(cp);
    if (!in) throw ConfigError(cp + ": no checkpoint to resume from");
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(in);
    } catch (const std::exception& e) {
      throw ConfigError(cp + ": unreadable checkpoint: " + e.what());
    }
    if (j.value("identity", nlohmann::json()) != identity)
      throw ConfigError(cp + ": checkpoint was made with a different profile, serial or plant (" +
                        j.value("identity", nlohmann::json()).dump() + "); start a new run instead");
    done = j.value("completed", std::vector<std::string>{});
    values.restore(j.value("values", nlohmann::json::object()));
    state = j.value("state", nlohmann::json::object());
    log_->info("resuming {}: {} phase(s) already complete", out_dir_, done.size());
  }
  for (const auto& p : phases) result.phases.push_back({p.id, p.title, "pending", "", "", ""});

  PhaseContext ctx{dev_, cancel, values, state, out_dir_, log_, progress_};
  std::size_t current = phases.size();
  try {
    log_->info("bring-up");
    bring_up(ctx);
    for (std::size_t i = 0; i < phases.size(); ++i) {
      const Phase& p = phases[i];
      PhaseRecord& rec = result.phases[i];
      if (std::find(done.begin(), done.end(), p.id) != done.end()) {
        rec.status = "skipped";
        rec.message = "completed in an earlier attempt (checkpoint)";
        if (progress_) progress_->phase_finished(p.id, "skipped", rec.message);
        continue;
      }
      current = i;
      cancel.throw_if_requested();
      rec.started = iso8601_utc_now();
      log_->info("phase {} start: {}", p.id, p.title);
      if (progress_) progress_->phase_started(i, phases.size(), p.id, p.title, p.planned_s);
      p.run(ctx);
      rec.finished = iso8601_utc_now();
      rec.status = "done";
      done.push_back(p.id);
      write_checkpoint(done, values, state, identity);
      log_->info("phase {} done (checkpointed)", p.id);
      if (progress_) progress_->phase_finished(p.id, "done", "");
      current = phases.size();
    }
    result.outcome = values.any_failed() ? RunOutcome::Fail : RunOutcome::Pass;
  } catch (const AbortedError& e) {
    result.outcome = RunOutcome::Aborted;
    result.message = cancel.requested() ? "aborted: " + cancel.reason() : e.what();
    log_->error("{}", result.message);
  } catch (const HardwareError& e) {
    result.outcome = RunOutcome::Error;
    result.message = std::string("hardware fault: ") + e.what();
    log_->error("{}", result.message);
  } catch (const ConfigError& e) {
    result.outcome = RunOutcome::Error;
    result.message = std::string("configuration error: ") + e.what();
    result.config_error = true;
    log_->error("{}", result.message);
  } catch (const std::exception& e) {
    result.outcome = RunOutcome::Error;
    result.message = std::string("error: ") + e.what();
    log_->error("{}", result.message);
  }
  if (current < phases.size()) {
    PhaseRecord& rec = result.phases[current];
    rec.status = result.outcome == RunOutcome::Aborted ? "aborted" : "failed";
    rec.finished = iso8601_utc_now();
    rec.message = result.message;
    if (progress_) progress_->phase_finished(rec.id, rec.status, rec.message);
  }
  safe_state(dev_, *log_, result.outcome == RunOutcome::Aborted || result.outcome == RunOutcome::Error);
  return result;
}

}  // namespace rig
