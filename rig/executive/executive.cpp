#include "rig/executive/executive.hpp"
#include "rig/core/json_unique.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "rig/core/errors.hpp"
#include "rig/executive/checkpoint_keys.hpp"
#include "rig/core/path_kind.hpp"

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

int exit_code_of(RunOutcome o, bool config_error) {
  switch (o) {
    case RunOutcome::Pass: return kExitPass;
    case RunOutcome::Fail: return kExitFail;
    case RunOutcome::Aborted: return kExitAborted;
    case RunOutcome::Error: return config_error ? kExitUsage : kExitHardware;
  }
  return kExitHardware;
}

std::optional<RunOutcome> outcome_named(std::string_view name) {
  for (const RunOutcome o : {RunOutcome::Pass, RunOutcome::Fail, RunOutcome::Aborted, RunOutcome::Error})
    if (name == to_string(o)) return o;
  return std::nullopt;
}

int RunResult::exit_code() const { return exit_code_of(outcome, config_error); }

void write_file_atomic(const std::string& path, const std::string& content) {
  write_file_staged(path, content);
  commit_staged(path);
}

// The rename is made durable too: a file's fsync keeps its bytes, its folder's keeps the name
// that points at them (POSIX: the rename lives in the directory), so a power cut after the run's
// exit status leaves the new file, not the old one or none (a review saw no fsync of the folder).
void commit_staged(const std::string& path) {
  std::filesystem::rename(path + ".tmp", path);
  const std::string dir = std::filesystem::path(path).parent_path().string();
  fsync_folder(dir.empty() ? "." : dir);
}

void fsync_folder(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // the file is in place; only its durability across a power cut is not forced
  ::fsync(fd);         // advisory here: some filesystems refuse a folder's fsync (EINVAL)
  ::close(fd);
}

void write_file_staged(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp";
  // A new file of our own: whatever lay at the temporary name (a FIFO would block the open, a
  // link would redirect the write) is removed first, and the open refuses anything in its place.
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(errno));
  // The OS's reason in every message (a full disk said only "write failed"), and no empty
  // temporary file left behind (a review).
  auto fail = [&](const char* what) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    ::unlink(tmp.c_str());
    throw std::runtime_error(std::string(what) + " " + tmp + ": " + why);
  };
  const char* p = content.data();
  std::size_t n = content.size();
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      fail("write failed:");
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  // A full disk may only say so when the data reach it (NFS, some FUSE filesystems).
  if (::fsync(fd) != 0 && errno != EINVAL) fail("write failed (fsync):");
  if (::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error("write failed (close): " + tmp + ": " + why);
  }
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
  // Said either way: after another master's command a client's own message reads "no halt sent by
  // this client"; the run's safe state still stops the table, and run.log says that it did.
  if (const std::string fate = dev.table.stop_fate(); !fate.empty())
    log.warn("safe state 1/3: {}", fate);
  else
    log.log(lvl, "safe state 1/3: stop delivered to the table (the run's safe state stops it whoever commanded it last)");
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
                                 const PhaseState& state, const nlohmann::json& identity,
                                 const std::vector<PhaseRecord>& records) {
  nlohmann::ordered_json j;
  j["schema"] = "rig.checkpoint/1";
  j["identity"] = identity;
  j["completed"] = done;
  j["values"] = values.to_json();
  j["state"] = state.save();
  // When each completed phase ran: a resume's passport gives its kept phases these times (they
  // were blank, and the ABORTED passport that had them is overwritten: a technician's review).
  nlohmann::ordered_json times = nlohmann::ordered_json::object();
  for (const PhaseRecord& r : records)
    if (std::find(done.begin(), done.end(), r.id) != done.end() && !r.started.empty())
      times[r.id] = {{"started", r.started}, {"finished", r.finished}};
  j["phase_times"] = times;
  if (const std::string lost = log_loss_ ? log_loss_() : ""; !lost.empty()) j[kLogMissingLinesKey] = lost;
  write_checkpoint_text(j);
}

void Executive::write_checkpoint_text(const nlohmann::ordered_json& j) {
  const std::string text = j.dump(1);
  checkpoint_write_failed_ = true;  // until both the seal and the file are written
  if (on_checkpoint_) on_checkpoint_(text);
  write_file_atomic(checkpoint_path(out_dir_), text);
  checkpoint_write_failed_ = false;
}

namespace {
// The shape iso8601_utc_now writes, 2026-11-22T05:30:12Z: what a checkpoint's phase times hold.
bool looks_iso8601(const std::string& t) {
  static constexpr std::string_view kShape = "dddd-dd-ddTdd:dd:ddZ";
  if (t.size() != kShape.size()) return false;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (kShape[i] == 'd' ? !std::isdigit(static_cast<unsigned char>(t[i])) : t[i] != kShape[i]) return false;
  return true;
}
}  // namespace

// A checkpoint is trusted only after it is checked (issue 13): the schema, the
// completed phases (a prefix of this procedure's phases), every measure of a
// completed phase present with the right types, and the procedure's state
// (PhaseState::restore checks its parts and the captures it names). Any
// damage is a ConfigError naming the file and the field: never a silent PASS.
Resumption Executive::read_checkpoint(const std::string& out_dir, const std::vector<Phase>& phases,
                                      MeasurementSet& values, PhaseState& state, const nlohmann::json& identity,
                                      spdlog::logger& log, bool allow_complete) {
  const std::string cp = checkpoint_path(out_dir);
  auto bad = [&cp](const std::string& field, const std::string& what) {
    // A record the checkpoint names (a capture, the loop test's file) that is gone is no damage to
    // the checkpoint: said so, with what brings the resume back (a review: "damaged checkpoint"
    // for one removed capture). The state's checks say "FIELD: PATH is missing" for exactly that,
    // and "... is not a regular file" for a folder or link in the record's place.
    const bool gone = what.empty() && field.ends_with(" is missing");
    const bool displaced = what.empty() && field.ends_with(" is not a regular file");
    return ConfigError(cp + ": " + field + (what.empty() ? "" : ": " + what) +
                       (gone        ? " (a record the checkpoint keeps is gone: put it back to resume, or start a new run)"
                        : displaced ? " (something else stands where a record the checkpoint keeps belongs: put the "
                                      "record back to resume, or start a new run)"
                                    : " (damaged checkpoint; start a new run)"));
  };
  // No checkpoint: the run stopped before its first phase completed (run.json is written
  // before any device opens). Nothing was measured, so the resume starts over from bring-up.
  if (path_kind(cp, "checkpoint") == PathKind::missing) {
    log.info("{}: no checkpoint (stopped before the first phase completed): starting from bring-up", cp);
    return {};
  }
  if (!std::filesystem::is_regular_file(cp)) throw ConfigError(cp + ": not a regular file (damaged run folder)");
  std::ifstream in(cp);
  if (!in) throw ConfigError(cp + ": cannot read the checkpoint");
  nlohmann::json j;
  try {
    j = parse_json_unique_keys(in);  // a key twice is refused, not read at its last
  } catch (const std::exception& e) {
    throw ConfigError(cp + ": unreadable checkpoint: " + e.what());
  }
  if (!j.is_object()) throw bad("(top level)", std::string("expected an object, found ") + j.type_name());
  static constexpr std::string_view kKeys[] = {"schema", "identity", "completed",         "values",
                                               "state",  "phase_times", kLogMissingLinesKey};
  if (const auto k = first_unknown_key(j, kKeys)) throw bad(*k, std::string(kNotACheckpointKey));
  // A run whose log lost lines is never resumed (app/cmd_run.cpp refuses the folder before it
  // reads the checkpoint); here only its form is checked.
  if (j.contains(kLogMissingLinesKey) && !j[kLogMissingLinesKey].is_string())
    throw bad(std::string(kLogMissingLinesKey), "expected a string");
  if (!j.contains("schema") || j["schema"] != "rig.checkpoint/1")
    throw bad("schema", "expected \"rig.checkpoint/1\", found " + (j.contains("schema") ? j["schema"].dump() : "nothing"));
  if (j.value("identity", nlohmann::json()) != identity) {
    // Name the first field that differs, with both values.
    const nlohmann::json mine = j.value("identity", nlohmann::json());
    std::string which = "identity";
    for (const auto& [k, v] : identity.items())
      if (!mine.is_object() || !mine.contains(k) || mine[k] != v) {
        // A profile's digest is not printed (a review: the message handed over the digest that
        // made an edited profile's resume pass, in a folder without a seal).
        which = "identity." + k + ": " + (mine.is_object() && mine.contains(k) ? mine[k].dump() : "missing") +
                (k == "profile_digest" ? std::string(", not this profile's") : ", this run's is " + v.dump());
        break;
      }
    // A resume reads the folder's own profile.toml: a digest that differs is that file edited
    // since the run started (a review: the message named no file).
    const bool profile = which.rfind("identity.profile_digest", 0) == 0;
    throw ConfigError(cp + ": " + which + ": checkpoint was made with a different profile, serial or plant" +
                      (profile ? " (" + out_dir + "/profile.toml, which a resume reads, is not the profile the run "
                                 "started with: edited since?)"
                               : std::string()) +
                      "; start a new run instead");
  }
  if (!j.contains("completed") || !j["completed"].is_array())
    throw bad("completed", "expected an array of phase ids");
  std::vector<std::string> done;
  for (std::size_t i = 0; i < j["completed"].size(); ++i) {
    const auto& id = j["completed"][i];
    const std::string field = "completed[" + std::to_string(i) + "]";
    if (!id.is_string()) throw bad(field, std::string("expected a phase id, found ") + id.type_name());
    // Phases complete in order: the completed list is a prefix of the procedure's phases.
    if (i >= phases.size() || id.get<std::string>() != phases[i].id)
      throw bad(field, "\"" + id.get<std::string>() + "\" is not phase " + std::to_string(i + 1) + " (" +
                           (i < phases.size() ? phases[i].id : std::string("none")) + ")");
    done.push_back(id.get<std::string>());
  }
  // phase_times (since 2026-12-02; older checkpoints have none): {id: {started, finished}}, ISO 8601.
  std::map<std::string, Resumption::Times> times;
  if (j.contains("phase_times")) {
    const auto& t = j["phase_times"];
    if (!t.is_object()) throw bad("phase_times", std::string("expected an object, found ") + t.type_name());
    for (const auto& [id, when] : t.items()) {
      for (const char* k : {"started", "finished"})
        if (!when.is_object() || !when.contains(k) || !when[k].is_string() || !looks_iso8601(when[k].get<std::string>()))
          throw bad("phase_times." + id + "." + k, "expected an ISO 8601 time");
      times[id] = {when["started"].get<std::string>(), when["finished"].get<std::string>()};
    }
  }
  if (!j.contains("values")) throw bad("values", "missing");
  try {
    values.restore(j["values"]);
  } catch (const std::invalid_argument& e) {
    throw bad(e.what(), "");
  }
  for (std::size_t i = 0; i < done.size(); ++i)
    for (const auto& m : phases[i].measures)
      if (!j["values"].contains(m.name))
        throw bad("values." + m.name, "missing, but phase '" + done[i] + "' that measures it is marked completed");
  if (!j.contains("state")) throw bad("state", "missing");
  try {
    state.restore(j["state"], done, out_dir);
  } catch (const std::invalid_argument& e) {
    throw bad(e.what(), "");
  } catch (const nlohmann::json::exception& e) {
    throw bad("state", e.what());
  }
  // A finished run has nothing to resume: running it again would only re-power the DUT and
  // rewrite a final passport with every phase "skipped". Refused before any device opens.
  if (!allow_complete && !phases.empty() && done.size() == phases.size())
    throw ConfigError(out_dir + ": the run is complete (all " + std::to_string(phases.size()) +
                      " phases are in checkpoint.json): nothing to resume; its passport stands");
  // What a from_records phase computed is computed again from the records the checks above
  // tied to the captures: its checkpointed values (checked for form only) are not kept.
  for (std::size_t i = 0; i < done.size(); ++i)
    if (phases[i].from_records)
      for (const auto& m : phases[i].measures)
        values.forget(m.name, "not computed again: the resume stopped before phase " + phases[i].id +
                                  ", which computes it from the kept records");
  // What the device alone measured has no record to compute it again from: that phase, and every
  // phase after it (the ones that may build on it), run again.
  // A phase whose hand-over the checkpoint does not hold runs again the same way.
  for (std::size_t i = 0; i < done.size(); ++i) {
    const bool measures_on_device = !phases[i].from_records && !phases[i].measures.empty();
    const bool held = state.holds(phases[i].id);
    if (!measures_on_device && held) continue;
    for (std::size_t k = i; k < done.size(); ++k) {
      for (const auto& m : phases[k].measures) values.forget(m.name);
      state.forget(phases[k].id);
    }
    if (measures_on_device)
      log.info("phase {} measures on the device: it runs again (its values are never taken from a checkpoint)",
               phases[i].id);
    else
      log.info("phase {}: the checkpoint keeps no record of it (an earlier version's checkpoint, or nothing recorded): "
               "it runs again",
               phases[i].id);
    done.resize(i);
    break;
  }
  log.info("resuming {}: {} phase(s) already complete", out_dir, done.size());
  // A phase not (or no longer) completed: its times are not kept.
  std::erase_if(times, [&](const auto& t) { return std::find(done.begin(), done.end(), t.first) == done.end(); });
  return {std::move(done), std::move(times)};
}

RunResult Executive::run(const std::function<void(PhaseContext&)>& bring_up, const std::vector<Phase>& phases,
                         MeasurementSet& values, PhaseState& state, const CancelToken& cancel, bool resume,
                         const nlohmann::json& identity) {
  const Resumption resumed = resume ? read_checkpoint(out_dir_, phases, values, state, identity, *log_) : Resumption{};
  return run(bring_up, phases, values, state, cancel, resumed, identity);
}

// The checkpoint on disk again, with the log's loss as it stands now, where lines were refused
// after it was written (the last phase's `done`, the safe state's): the ending's passport may be
// refused too, and the checkpoint is then the only file that says the log is short. Read back
// rather than kept from its write: this runs only where lines were lost, and a resume stopped
// before its first checkpoint records it in the earlier attempt's (a review: nothing said so).
// A write the disk refuses leaves the checkpoint as it was, said in the log's own words (it may
// reach the console only).
void Executive::record_the_log_loss() {
  // Not after a checkpoint write that failed: each write seals its text first, and a second
  // failure would leave neither seal holding the checkpoint on disk (a review).
  if (!log_loss_ || checkpoint_write_failed_) return;
  const std::string lost = log_loss_();
  if (lost.empty()) return;
  try {
    const std::string cp = checkpoint_path(out_dir_);
    if (path_kind(cp, "checkpoint") != PathKind::file) return;  // none: nothing kept, a resume starts anew
    std::ifstream in(cp);
    nlohmann::ordered_json j = nlohmann::ordered_json::parse(in, nullptr, false);
    if (!j.is_object() || j.value(kLogMissingLinesKey, std::string()) == lost) return;
    j[kLogMissingLinesKey] = lost;
    write_checkpoint_text(j);
  } catch (const std::exception& e) {
    log_->error("{} not recorded in the checkpoint: {}", lost, e.what());
  }
}

namespace {
constexpr const char* kKeptFromCheckpoint = "completed in an earlier attempt (checkpoint)";
}  // namespace

RunResult Executive::run(const std::function<void(PhaseContext&)>& bring_up, const std::vector<Phase>& phases,
                         MeasurementSet& values, PhaseState& state, const CancelToken& cancel,
                         const Resumption& resumed, const nlohmann::json& identity) {
  RunResult result;
  std::vector<std::string> done = resumed.completed;
  std::size_t checkpointed = done.size();  // what the folder's checkpoint holds (RunResult::checkpointed)
  for (const auto& p : phases) result.phases.push_back({p.id, p.title, "pending", "", "", ""});
  // A resume's kept phases are kept from the start: a stop during bring-up (or the emulation's
  // fast-forward) wrote every phase "pending", though the checkpoint holds them (a review).
  auto kept = [&](std::size_t i) {
    return !phases[i].from_records && std::find(done.begin(), done.end(), phases[i].id) != done.end();
  };
  for (std::size_t i = 0; i < phases.size(); ++i)
    if (kept(i)) {
      PhaseRecord& r = result.phases[i];
      r.status = "skipped", r.message = kKeptFromCheckpoint;
      if (const auto t = resumed.times.find(r.id); t != resumed.times.end())
        r.started = t->second.started, r.finished = t->second.finished;
    }

  PhaseContext ctx{dev_, cancel, values, out_dir_, log_, progress_, {}};
  std::size_t current = phases.size();
  bool every_phase_ran = false;  // the loop below went through its last phase
  try {
    if (unopened_.empty()) {
      log_->info("bring-up");
      bring_up(ctx);
    } else {
      log_->info("no device opened: {}", unopened_);
      if (progress_) progress_->log("  no device opened: " + unopened_);  // where bring-up says "DUT power on"
      for (std::size_t i = 0; i < phases.size(); ++i)
        if (!phases[i].from_records && phases[i].uses_devices && !kept(i))
          throw std::logic_error("phase " + phases[i].id + " uses the devices, but none is open");
    }
    for (std::size_t i = 0; i < phases.size(); ++i) {
      const Phase& p = phases[i];
      PhaseRecord& rec = result.phases[i];
      const bool was_done = std::find(done.begin(), done.end(), p.id) != done.end();
      if (kept(i)) {
        if (progress_) progress_->phase_finished(p.id, "skipped", rec.message);
        continue;
      }
      current = i;
      cancel.throw_if_requested();
      rec.started = iso8601_utc_now();
      log_->info("phase {} start: {}", p.id, p.title);
      if (progress_) progress_->phase_started(i, phases.size(), p.id, p.title, p.planned_s);
      {
        std::vector<std::string> names;
        for (const auto& m : p.measures) names.push_back(m.name);
        values.set_scope(p.id, std::move(names));  // a phase sets only what it declares
      }
      ctx.not_run.clear();
      try {
        p.run(ctx);
      } catch (const ConfigError& e) {
        // A phase that computes from the run's own records finds them damaged only if they changed
        // while the run went on (a resume checked them before any device opened): the folder, not
        // the configuration (a review: loop-test.csv edited mid-run ended "configuration error",
        // exit 2; contracts.md: records changed after their writer closed them are exit 4).
        if (!p.from_records) throw;
        throw RecordsChangedError(std::string("the run's records changed while it went on: ") + e.what());
      }
      values.set_scope({}, {});
      rec.finished = iso8601_utc_now();
      rec.status = ctx.not_run.empty() ? "done" : "skipped";
      rec.message = std::exchange(ctx.not_run, {});
      if (was_done) rec.message = "computed again from the kept records (resume)";
      else done.push_back(p.id);  // `done` stays a prefix of the phases, in their order
      write_checkpoint(done, values, state, identity, result.phases);
      checkpointed = done.size();  // only once written: a failed write keeps the count before it
      log_->info("phase {} done{} (checkpointed)", p.id, was_done ? ", computed again from the kept records" : "");
      if (progress_) progress_->phase_finished(p.id, rec.status, rec.message);
      current = phases.size();
    }
    every_phase_ran = true;
    // A signal between the last phase and here is still an abort (issue 13: late signals).
    cancel.throw_if_requested();
    values.judge_all(true);
    result.outcome = values.any_failed() ? RunOutcome::Fail : RunOutcome::Pass;
  } catch (const AbortedError& e) {
    result.outcome = RunOutcome::Aborted;
    // Every phase ran (a signal the last phase did not act on): said as a signal after the last
    // phase is (app/cmd_run.cpp), since its values are judged as a complete run's.
    result.message = cancel.requested() ? (every_phase_ran ? "aborted after the last phase: " : "aborted: ") + cancel.reason()
                                        : e.what();
    log_->error("{}", result.message);
  } catch (const RecordsChangedError& e) {  // before HardwareError, its base
    result.outcome = RunOutcome::Error;
    result.message = std::string("error: ") + e.what();
    result.records_changed = true;
    log_->error("{}", e.what());  // the level says "error" (it read "error error: ...")
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
    log_->error("{}", e.what());
  }
  values.set_scope({}, {});
  // Stopped early: what was measured is judged, the rest stays UNSET. Stopped after every phase
  // ran (a signal before the verdict): judged as a complete run, so a required value that could
  // not be measured is FAIL, as when the signal comes after the verdict (app/cmd_run.cpp).
  if (result.outcome != RunOutcome::Pass && result.outcome != RunOutcome::Fail)
    values.judge_all(every_phase_ran);
  if (current < phases.size()) {
    PhaseRecord& rec = result.phases[current];
    rec.status = result.outcome == RunOutcome::Aborted ? "aborted" : "failed";
    rec.finished = iso8601_utc_now();
    rec.message = result.message;
    if (progress_) progress_->phase_finished(rec.id, rec.status, rec.message);
  }
  result.checkpointed = checkpointed;
  if (unopened_.empty())  // nothing opened, nothing moved or powered: no safe state to reach
    safe_state(dev_, *log_, result.outcome == RunOutcome::Aborted || result.outcome == RunOutcome::Error);
  if (!result.config_error) record_the_log_loss();  // a configuration error is started anew, not resumed
  return result;
}

}  // namespace rig
