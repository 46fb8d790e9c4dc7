// The procedure engine, in the manner of OpenHTF's phases and plugs: a list of
// phases run in order against the device seams, each completed phase
// checkpointed in the run folder, and a guaranteed safe-state teardown on
// every exit path (normal end, abort, fault): table stopped, stream stopped,
// DUT powered off, in that order, each step logged.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/logger.h>

#include "rig/core/cancel.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/gpio.hpp"
#include "rig/core/log_loss.hpp"
#include "rig/core/table.hpp"
#include "rig/executive/measurement.hpp"

namespace rig {

// The plugs a procedure runs against (real or emulated backends behind them).
struct Devices {
  RotaryTable& table;
  DutLink& dut;
  RigIo& io;
  Clock& clock;
  std::string plant;  // "emulated" | "hardware"
};

// Progress reporting from inside a phase (fraction of the phase's planned time).
class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  virtual void phase_started(std::size_t index, std::size_t count, const std::string& id, const std::string& title,
                             double planned_s) = 0;
  virtual void phase_progress(double fraction, double sim_now_s) = 0;
  virtual void phase_finished(const std::string& id, const std::string& status, const std::string& message) = 0;
  virtual void log(const std::string& line) = 0;
};

struct PhaseContext {
  Devices& dev;
  CancelToken cancel;
  MeasurementSet& values;
  std::string out_dir;
  std::shared_ptr<spdlog::logger> log;
  ProgressSink* progress = nullptr;
  // Set by a phase that found its step not possible on this device (a DUT that does not run the
  // loop test): its record reads "skipped" with this reason, not "done" with none (a review).
  // It still counts as completed: there is nothing to take again on a resume.
  std::string not_run;
  void report(double fraction) const {
    if (progress) progress->phase_progress(fraction, dev.clock.now_s());
  }
};

struct Phase {
  std::string id;
  std::string title;
  double planned_s = 0;  // planned duration in device (simulated or real) time, for ETA
  std::function<void(PhaseContext&)> run;
  std::vector<MeasurementSpec> measures = {};  // what the phase sets in PhaseContext::values (declared before the run)
  // Computes only from what earlier phases recorded (captures, run means) and touches no device.
  // A resume runs it again rather than taking its values from the checkpoint: a value in the
  // passport is then always computed from the kept captures, never read back from a file
  // anyone could have edited.
  bool from_records = false;
  // Whether a phase that is not from_records uses the devices here: false for one whose only device
  // call is answered without them (the loop test a DUT's link refuses from its options). A resume
  // left with only such phases and from_records ones opens none (without_devices).
  bool uses_devices = true;
};

// What the phases hand on to each other (typed by the procedure), saved with
// every checkpoint. The executive only stores and restores it.
class PhaseState {
 public:
  virtual ~PhaseState() = default;
  virtual nlohmann::json save() const = 0;
  // From a checkpoint's "state": throws std::invalid_argument naming the field ("state.bias.sign_u10: ...")
  // when `j` is not what the phases in `completed` leave behind (wrong type, missing part, a capture it
  // names missing or not matching).
  // `run_dir` is the run folder the captures it names are in.
  virtual void restore(const nlohmann::json& j, const std::vector<std::string>& completed,
                       const std::string& run_dir) = 0;
  // Drops what phase `phase_id` handed on, as if it had not run (a resume runs it again). A state
  // whose phases hand nothing on has nothing to drop.
  virtual void forget(const std::string& /*phase_id*/) {}
  // Whether the restored state holds what completed phase `phase_id` handed on. A phase it does
  // not hold (a checkpoint written before the phase kept its records, or a phase that recorded
  // nothing) runs again, with every phase after it, as a phase that measures on the device does.
  virtual bool holds(const std::string& /*phase_id*/) const { return true; }
};

// A state for procedures whose phases hand nothing on.
class NoPhaseState final : public PhaseState {
 public:
  nlohmann::json save() const override { return nlohmann::json::object(); }
  void restore(const nlohmann::json&, const std::vector<std::string>&, const std::string&) override {}
};

struct PhaseRecord {
  std::string id, title, status, started, finished, message;  // status: done|failed|aborted|skipped|pending
};

enum class RunOutcome { Pass, Fail, Aborted, Error };
const char* to_string(RunOutcome o);
// The exit code of a run that ended so (docs/contracts.md); an ERROR of bad configuration is 2.
int exit_code_of(RunOutcome o, bool config_error = false);
// The outcome a passport names, as to_string writes it; nullopt for any other text.
std::optional<RunOutcome> outcome_named(std::string_view name);

struct RunResult {
  RunOutcome outcome = RunOutcome::Error;
  std::string message;  // abort reason or fault text
  bool config_error = false;  // an Error caused by bad configuration exits 2, not 4
  // An Error because a phase computing from the run's records found them changed while the run
  // went on: a resume refuses such a folder, so none is offered.
  bool records_changed = false;
  std::vector<PhaseRecord> phases;
  // The phases the folder's checkpoint holds at the end: what a resume of it starts from
  // (a from_records phase not yet computed again by this resume counts, as its records do).
  std::size_t checkpointed = 0;
  int exit_code() const;
};

// Where a resume starts, as read_checkpoint() found it: the completed phases' ids in the
// procedure's order, and the times the checkpoint gave them (none in a checkpoint written
// before it kept phase_times).
struct Resumption {
  struct Times {
    std::string started, finished;  // ISO 8601, checked
  };
  std::vector<std::string> completed;
  std::map<std::string, Times> times;
};

class Executive {
 public:
  Executive(Devices& dev, std::string out_dir, std::shared_ptr<spdlog::logger> log, ProgressSink* progress);

  // Bring-up runs on every start, resume included (power, homing: hardware
  // state is never taken from a checkpoint), unless without_devices() said none is open. Phases already in the checkpoint
  // are skipped when `resume` is set, except those computed from records (Phase::from_records),
  // which run again; a run folder without a checkpoint (stopped before its first phase
  // completed) resumes from bring-up. `identity` (profile digest, serial, plant) must match the
  // checkpoint's, and the checkpoint must pass read_checkpoint()'s checks (else ConfigError
  // naming the file and field: exit 2). `values` must hold the
  // declarations of every phase's measures. Outcomes are judged once, at the end
  // (MeasurementSet::judge_all), whatever the path: a resumed run is judged
  // exactly as an uninterrupted one. A cancellation requested after the last
  // phase still ends the run ABORTED.
  RunResult run(const std::function<void(PhaseContext&)>& bring_up, const std::vector<Phase>& phases,
                MeasurementSet& values, PhaseState& state, const CancelToken& cancel, bool resume,
                const nlohmann::json& identity);
  // The same, resuming where read_checkpoint() said (nothing completed: a fresh run).
  RunResult run(const std::function<void(PhaseContext&)>& bring_up, const std::vector<Phase>& phases,
                MeasurementSet& values, PhaseState& state, const CancelToken& cancel, const Resumption& resumed,
                const nlohmann::json& identity);

  // A resume's starting point, read before any device opens. The checkpoint in `out_dir` is
  // checked (schema, `identity`, the completed phases a prefix of `phases`, every measure of a
  // completed phase present with the right types, PhaseState::restore with the captures it
  // names) and `values` and `state` restored; the values of completed from_records phases are
  // then forgotten, as those phases run again. Returns the completed phase ids with their times
  // (none without a checkpoint). A completed phase that measures on the device (declares measures and is not
  // from_records: the loop test) cannot have its values taken from a file either: it and every
  // phase after it are returned as not completed, their values and state forgotten, and run
  // again. Throws ConfigError naming the file and the field on any damage, and when every phase
  // is complete unless `allow_complete`: the caller allows it where the run has no final verdict
  // (an abort after the last phase).
  static Resumption read_checkpoint(const std::string& out_dir, const std::vector<Phase>& phases,
                                                  MeasurementSet& values, PhaseState& state,
                                                  const nlohmann::json& identity, spdlog::logger& log,
                                                  bool allow_complete = false);

  // The devices are not open: every phase left computes from the run's records (a resume of a run
  // stopped at its ending). run() then neither brings them up
  // nor puts them in the safe state, and says `why` in the log; a phase left that would use them
  // is a programming error (the caller opens them where one is left).
  void without_devices(std::string why) { unopened_ = std::move(why); }

  // The safe-state sequence; public so signal paths and tests can call it.
  // `abnormal` (abort or fault) logs the steps as warnings, otherwise as info.
  static void safe_state(Devices& dev, spdlog::logger& log, bool abnormal = true);

  static std::string checkpoint_path(const std::string& out_dir);

  // Called with each checkpoint's text before the file is replaced: whoever seals the run
  // folder (app, rig/seal) seals the new text first, so a stop between the two leaves a seal
  // that still holds for one of the two checkpoints.
  void on_checkpoint(std::function<void(const std::string& text)> f) { on_checkpoint_ = std::move(f); }

  // What the run's log is missing (lines the disk refused), "" while it is whole. A checkpoint
  // written while it says something records it (`log_missing_lines`), and so does the last
  // checkpoint again once the run has ended: the loss is kept where the disk still took it, even
  // when the ending's passport is refused too, and a resume refuses that folder (a verdict beside a
  // hole in the account is no verdict). A checkpoint holding it is never resumed from.
  void log_loss_from(std::function<std::string()> f) { log_loss_ = std::move(f); }
  // The checkpoint on disk written again with the log's loss as it stands now, where it does not
  // say so already (run() calls it as it ends; the run's ending again before its passport, whose
  // lines may be refused too). A write the disk refuses leaves the checkpoint as it was.
  void record_the_log_loss();

 private:
  void write_checkpoint(const std::vector<std::string>& done, const MeasurementSet& values,
                        const PhaseState& state, const nlohmann::json& identity,
                        const std::vector<PhaseRecord>& records);
  void write_checkpoint_text(const nlohmann::ordered_json& j);
  std::function<std::string()> log_loss_;
  std::string unopened_;  // why no device is open ("" while they are)
  bool checkpoint_write_failed_ = false;  // the last write of the checkpoint (or its seal) threw
  Devices& dev_;
  std::string out_dir_;
  std::shared_ptr<spdlog::logger> log_;
  ProgressSink* progress_;
  std::function<void(const std::string&)> on_checkpoint_;
};

// Atomic file replace: write to a temp file, fsync, rename.
void write_file_atomic(const std::string& path, const std::string& content);
// The same in two steps: write_file_staged writes and fsyncs PATH.tmp (where a full disk fails),
// commit_staged renames it into place (a run's ending puts several files in place at its end).
void write_file_staged(const std::string& path, const std::string& content);
void commit_staged(const std::string& path);
// fsync of a folder, so a name made or renamed in it survives a power cut (best effort: some
// file systems refuse a folder's fsync).
void fsync_folder(const std::string& dir);

}  // namespace rig
