// The station's seal on a run folder (rig/seal, docs/seal.md), as `rig run` and `rig verify`
// use it: where the key comes from, which files a run seals when, and the checks a resume makes
// before it trusts the folder.
#pragma once
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "rig/core/log_loss.hpp"
#include "rig/seal/seal.hpp"

namespace rig::cli {

// --seal-key FILE or RIG_SEAL_KEY, else none: the station names its key itself, never the run
// folder. `given`: the option or the variable was set, so an empty value is an error, not "no
// key". Loaded and checked before any device opens.
std::optional<seal::Key> station_key(const std::string& option, bool given);

// Seals the files the rig wrote: `files` (relative to `dir`; only what the run itself wrote,
// never what else lies in the folder), with `checkpoint_text` sealed as checkpoint.json (about to
// be written) and `outcome` the passport's once final. The seal it replaces is kept as
// seal.prev.json until the next one, so a stop between the seal and the checkpoint leaves one
// that holds. ConfigError when it cannot be written (the run stops: exit 2).
void seal_run_folder(const std::string& dir, const seal::Key& k, const std::vector<std::string>& files,
                     const std::optional<std::string>& checkpoint_text = std::nullopt,
                     const std::string& outcome = "");
// The run's `records` (relative to `dir`) that seal.json vouches for and that are no longer as it
// sealed them ("FILE: changed since it was sealed"), or the seal's own problem when it no longer
// holds. The run's end asks it (with a key): an edit that kept a record's size and modification
// time passes the stamps, never the MAC sealed when the record closed.
std::vector<std::string> records_unlike_their_seal(const std::string& dir, const seal::Key& k,
                                                   const std::vector<std::string>& records);
// `rig verify`'s whole check of a run folder (cmd_verify.cpp): the seal with its files, nothing
// added after it, a final seal whose outcome the passport states, the loop test's records as the
// sealed checkpoint describes them. `ok` when all hold; `problems` one line each otherwise.
seal::Check check_run_folder_seal(const std::string& dir, const seal::Key& key);
// After the final seal: the previous one is no longer needed.
void drop_previous_seal(const std::string& dir);
// The files seal.json lists (relative to `dir`); empty when there is none or it is unreadable.
std::vector<std::string> sealed_files(const std::string& dir);

// What every ending of a run writes (README, "The run folder"), and so what a resume writes
// again: a resume reads none of them, and the rig replaces each, so each must be a file.
inline constexpr const char* kRunOutputs[] = {"passport.json", "junit.xml", "analysis.json", "report.html"};

// A file the run writes once (its invocation, profile, captures, the loop test's records), as
// against checkpoint.json and what every ending writes again (kRunOutputs): a seal carries the
// MAC it first took of a record (seal_run_folder).
inline bool written_by_every_ending(const std::string& rel) {
  for (const char* o : kRunOutputs)
    if (rel == o) return true;
  return false;
}
inline bool is_record(const std::string& rel) { return rel != "checkpoint.json" && !written_by_every_ending(rel); }

// The ending's steps after the passport is in place, until they are done: junit.xml put in place,
// report.html where it could not be written, the final seal and the history row (one per line). A dot file: outside the seal (outside_the_seal).
inline constexpr const char* kEndingPending = ".ending-pending";
// The ending's files are being written: the passport in place, if any, is an earlier ending's,
// and nothing listed with it is that ending's (first in the list until the passport's rename).
inline constexpr const char* kStepEnding = "ending";
inline constexpr const char* kStepJunit = "junit";      // junit.xml put in place (listed until it is)
inline constexpr const char* kStepReport = "report";    // its lines: report.html (a full disk)
inline constexpr const char* kStepSeal = "seal";
inline constexpr const char* kStepHistory = "history";
// The steps `dir`'s .ending-pending lists, in order; nothing when there is no such file. (Inline:
// `rig history --record` reads it too, from a library without the seal's code.)
inline std::optional<std::vector<std::string>> pending_steps(const std::string& dir) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(dir + "/" + kEndingPending, ec)) return std::nullopt;
  std::ifstream in(dir + "/" + kEndingPending);
  std::vector<std::string> steps;
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) steps.push_back(line);
  return steps;
}

// Whether every file the seal `c` read holds as sealed (false where it read none).
bool all_files_hold(const seal::Check& c);

// Whether `dir`'s final seal was refused (a full disk), as `c` (check_run_folder_seal with `key`)
// found it: its ending lists the seal as still to do, and the seal that stands is the last
// checkpoint's with every file it sealed holding: seal.prev.json where no seal.json stands, or a
// seal.json its rotation left (the rename refused). Said as an ending not finished, not as a
// folder changed behind the station; a record changed since is said as that (a review).
bool final_seal_owed(const std::string& dir, const seal::Check& c, const seal::Key& key);

// What a command line handed over names of the station's key: ` --seal-key FILE` as given, or
// nothing where it came from RIG_SEAL_KEY (set already where the line is run).
std::string seal_key_words(const std::string& seal_key);

// `dir`'s passport.json as parsed; nullopt when it is missing, not a regular file (a FIFO is
// never opened), not JSON or not an object.
std::optional<nlohmann::json> read_passport(const std::string& dir);

// The outcome passport.json states; nullopt when read_passport has none or it names none.
std::optional<std::string> passport_outcome(const std::string& dir);

// Whether an outcome is a verdict (PASS or FAIL), as against a stopped run's ABORTED or ERROR.
inline bool is_verdict(std::string_view outcome) { return outcome == "PASS" || outcome == "FAIL"; }

// A run's verdict, once its passport says PASS or FAIL; "" otherwise. A run whose phases are all
// recorded but whose passport says ABORTED or ERROR (a signal after the last phase), or that has
// none (killed before it was written), is finished by a resume that only computes.
std::string verdict_of(const std::string& dir);

// How an ending names a run.log the disk refused lines of, in its reason (aborted_reason).
inline constexpr std::string_view kLogMissingLines = "run.log is missing lines";

// The reason of an ERROR or ABORTED ending whose run.log lost lines; "" otherwise. Such a run has
// no resume: its ending would give a verdict beside a log with a hole in the account.
std::string earlier_log_missing_lines(const std::string& dir);

// A run's final outcome: its verdict (verdict_of), or the ERROR or ABORTED ending of a run whose
// log is missing lines, which has no resume (earlier_log_missing_lines): its passport stands, and
// what its ending left undone (report.html, junit.xml, the history row: a full disk) is finished
// by `rig run --resume` as a verdict's is, nothing measured or computed again (a code review: that
// ending said "rig run --resume writes it", and the resume was refused). "" when the run can
// still go on.
std::string final_outcome_of(const std::string& dir);

// Whether `rig run --resume` takes up the ending `dir`'s .ending-pending lists (`steps`): every
// run's but one with no resume (its log missing lines) whose list names its own files (`ending`)
// or a final seal not written, which only computing the ending again would give (a code review:
// `rig verify` advised that resume, and it was refused).
bool a_resume_finishes(const std::string& dir, const std::vector<std::string>& steps);
// What `rig verify` and `rig history --record` say of such an ending instead of the resume.
inline constexpr std::string_view kNothingFinishesIt =
    "nothing finishes it: the run has no resume (its run.log is missing lines)";

// The seal `dir` holds: "seal.json", else "seal.prev.json" (a stop between two seals may leave
// only the previous one), else none. A link or any other entry of that name counts: the rig makes
// none, and the checks that follow refuse it.
std::optional<std::string> seal_in(const std::string& dir);

// Before a resume trusts `dir`, first of all (before run.json is read): with a key, seal.json or
// seal.prev.json must be this key's, its list and outcome whole, and every file it lists that a
// resume reads (run.json, profile.toml, checkpoint.json, the captures) present, a regular file and
// unchanged (what every ending writes again need not be); an unsealed folder is refused (sealing
// it now would vouch for files the key never saw), and so is a sealed PASS or FAIL (the sealed
// verdict stands, whatever passport.json says now). Without a key a sealed folder is refused (a
// resume would leave it unsealed). ConfigError naming what does not hold. A sealed PASS or FAIL
// whose ending was stopped after the seal (`pending_ending`: .ending-pending in the folder) is
// not refused: true is returned, and the caller finishes that ending (its history row). So is a
// sealed ERROR or ABORTED ending that stopped the run for good (`ended_for_good`: its run.log is
// missing lines, so it has no resume), whose report or history row is what is left. Such a final
// ending is finished only where every file its seal lists but report.html (which the finish may
// draw again) is as sealed, the ending's own junit.xml and analysis.json too: else ConfigError.
bool check_seal_before_resume(const std::string& dir, const std::optional<seal::Key>& k, bool pending_ending,
                              bool ended_for_good = false);

// The files of `dir` no seal is asked to cover: run.log (appended to after the last seal), the
// seals, hidden and temporary files, and a capture a resume set aside
// (captures/<name>.cap.interrupted-<N>: what it holds was never checked). `rig verify` names
// every other file the seal does not list as added after it.
bool outside_the_seal(const std::string& rel);

}  // namespace rig::cli
