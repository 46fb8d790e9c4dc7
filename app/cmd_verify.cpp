// rig verify DIR --seal-key FILE: is the run folder as the station sealed it (docs/seal.md)?
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "app/commands.hpp"
#include "app/folder_lock.hpp"
#include "rig/core/json_unique.hpp"
#include "app/run_seal.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/path_kind.hpp"

namespace rig::cli {

namespace {

// Every entry of `dir` but what no seal is asked to cover (outside_the_seal), without following
// links: a link, a FIFO or a file the seal does not list was put there after it. `outside` (if
// given) gets what no seal covers, but the log, the seals and the ending's list: set-aside
// records, temporary and hidden files, which `rig verify` names without judging them.
std::vector<std::string> entries_in(const std::string& dir, std::vector<std::string>* outside = nullptr) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string rel = it->path().lexically_relative(dir).generic_string();
    if (outside_the_seal(rel)) {
      if (it->is_directory() && !it->is_symlink()) it.disable_recursion_pending();
      if (outside && rel != "run.log" && rel != "seal.json" && rel != "seal.prev.json" && rel != kEndingPending)
        outside->push_back(shown_text(rel) + (it->is_directory() && !it->is_symlink() ? "/" : ""));  // \xNN: a newline in a name made a line of its own (a re-test)
      continue;
    }
    if (it->is_directory() && !it->is_symlink()) {
      // A folder with nothing in it holds no record: named beside what no seal covers, not judged
      // (an added empty folder went unmentioned: a technician's re-test).
      std::error_code ec;
      // The rig's own captures/ is empty until its first record.
      if (outside && rel != "captures" && fs::is_empty(it->path(), ec) && !ec)
        outside->push_back(shown_text(rel) + "/ (empty)");
      continue;
    }
    out.push_back(rel);
  }
  std::sort(out.begin(), out.end());
  if (outside) std::sort(outside->begin(), outside->end());
  return out;
}

// The loop test's records must be the ones the sealed checkpoint describes (their CRC-32 and
// what the file states): the seal vouches for the bytes it read, and a file swapped after the
// figures were read from it would otherwise verify. "" when they are, or when there are none.
std::string loop_records_problem(const std::string& dir) {
  try {
    std::ifstream in(dir + "/checkpoint.json");
    const nlohmann::json cp = parse_json_unique_keys(in);
    const acceptance::DutState st = acceptance::dut_state_from_json(cp.at("state"));
    if (st.loop_test) acceptance::check_loop_record(*st.loop_test, dir);
  } catch (const std::exception& e) {
    return std::string(acceptance::kLoopTestFile) + ": not the records the checkpoint describes (" + e.what() + ")";
  }
  return "";
}

}  // namespace

seal::Check check_run_folder_seal(const std::string& dir, const seal::Key& key) {
  // The passport is what a seal is for: a folder whose seal leaves it out is not verified.
  seal::Check c = seal::check_seal(dir, dir + "/seal.json", key, {"passport.json"});
  if (!c.files.empty()) {  // the seal was read: anything it does not list was added after it
    // Once per file: the check names a passport the seal leaves out already (it was listed twice, a re-test).
    const auto named = [&](const std::string& f) {
      return std::any_of(c.problems.begin(), c.problems.end(), [&](const std::string& p) { return p.rfind(f + ": ", 0) == 0; });
    };
    for (const std::string& f : entries_in(dir))
      if (std::none_of(c.files.begin(), c.files.end(), [&](const auto& s) { return s.first == f; }) && !named(f))
        c.problems.push_back(shown_text(f) + ": not sealed (added after the seal)");  // a newline in a name is seen
    if (c.outcome.empty()) c.problems.push_back("seal.json: not a final seal (the run has not ended)");
    const bool passport_ok = std::any_of(c.files.begin(), c.files.end(), [](const auto& e) {
      return e.first == "passport.json" && e.second == seal::FileState::Ok;  // a regular file, as sealed
    });
    const bool checkpoint_ok = std::any_of(c.files.begin(), c.files.end(), [](const auto& e) {
      return e.first == "checkpoint.json" && e.second == seal::FileState::Ok;
    });
    if (checkpoint_ok)
      if (const std::string p = loop_records_problem(dir); !p.empty()) c.problems.push_back(p);
    if (passport_ok) {  // the passport must state the outcome the seal states
      const std::optional<std::string> o = passport_outcome(dir);
      if (!o) c.problems.push_back("passport.json: unreadable");
      else if (!c.outcome.empty() && *o != c.outcome)
        c.problems.push_back("passport.json: outcome " + *o + ", the seal states " + c.outcome);
    }
    c.ok = c.problems.empty();
  }
  return c;
}

namespace {

int do_verify(const std::string& dir, const std::string& key_path, bool given) {
  if (path_kind(dir, "rig verify") != PathKind::directory) throw ConfigError(dir + ": not a run folder");
  const std::optional<seal::Key> key = station_key(key_path, given);
  if (!key) throw ConfigError("rig verify needs the station's key: --seal-key FILE or RIG_SEAL_KEY");
  const seal::Check c = check_run_folder_seal(dir, *key);
  std::cout << fmt::format("{}: seal.json, key {} ({}){}\n", dir, key->id, key->path,
                           c.outcome.empty() ? std::string() : ", sealed outcome " + c.outcome);
  for (const auto& [f, state] : c.files)
    std::cout << fmt::format("  {:<8} {}\n",
                             state == seal::FileState::Ok        ? "ok"
                             : state == seal::FileState::Changed ? "CHANGED"
                             : state == seal::FileState::Missing ? "MISSING"
                                                                 : "NOT-FILE",
                             shown_text(f));
  // A final seal the disk refused (the ending lists `seal`, no seal.json) is an ending not finished,
  // not a folder changed behind the station (a technician's review read tampering into it).
  const bool seal_owed = final_seal_owed(dir, c, *key);
  // Its missing seal.json said as that, not as a folder never sealed (session 66's list).
  for (const std::string& p : c.problems)
    std::cout << "  problem: "
              << (seal_owed && p.ends_with(seal::kSealMissing)
                      ? p.substr(0, p.size() - seal::kSealMissing.size()) +
                            ": missing: the final seal was not written (seal.prev.json, the last checkpoint's seal, "
                            "holds what it sealed)"
                      : p)
              << "\n";
  // A run stopped before its ending (a kill, a power cut) holds a checkpoint's seal: what it
  // sealed holds, what it recorded since is not sealed yet. Said as such, with the way on, not as a
  // folder changed behind the station's back (a technician's review read tampering into it).
  const bool not_ended = !c.ok && c.outcome.empty() && all_files_hold(c) && !pending_steps(dir);
  // A folder a rig process holds now (a run or resume, or a report or history record being
  // written: the folder's lock) is not sent a resume it would refuse (a code review: "goes on with
  // the run" was said of a live run's folder).
  const bool live = FolderLock::held_elsewhere(dir);
  // A run whose checkpoint records that its log lost lines has no resume (a technician's review:
  // verify advised one, and it was refused).
  const std::string log_short = checkpoint_log_missing_lines(dir);
  std::cout << (c.ok ? fmt::format("verified: {} files as the station sealed them, outcome {} (the seal says who wrote "
                                   "them; the outcome is the passport's)\n",
                                   c.files.size(), c.outcome)
                : not_ended
                    ? fmt::format("NOT verified: the run has not ended (its last seal is a checkpoint's, not a final "
                                  "one): the {} files it sealed hold, what was recorded after it is not sealed; {}\n",
                                  c.files.size(),
                                  live ? "a rig process holds the folder now (a run or resume, a report or a "
                                         "history record: its lock): verify it once that process has ended"
                                  : !log_short.empty()
                                      ? "its checkpoint records that " + log_short +
                                            ": no resume goes on with it (start a new run)"
                                      : "`rig run --resume " + shell_word(dir) + seal_key_words(key_path) +
                                            "` goes on with the run")
                : seal_owed ? std::string("NOT verified: the run's final seal was not written (its ending lists it as "
                                          "still to do; the seal that stands is its last checkpoint's)\n")
                    : std::string("NOT verified: the folder is not as the station sealed it\n"));
  // A stopped run's ending (ABORTED, ERROR) verifies as sealed: what was kept holds, and the run
  // may go on. Said, with the command that tells whether and how (a technician's review: verify
  // said "verified ... outcome ABORTED" and no more).
  if (c.ok && !live && !is_verdict(c.outcome))
    std::cout << fmt::format("note: the run stopped before its verdict (outcome {}): `rig run --dry-run --resume {}{}` "
                             "says whether and how it goes on\n",
                             c.outcome, shell_word(dir), seal_key_words(key_path));
  // What the seal holds may be whole while the ending is not (report.html a full disk kept out,
  // the history row): said, with how to finish it (a review: verify was silent on it).
  // The key only where the folder is sealed: a resume of an unsealed folder refuses one (a review).
  // What no seal covers is named, not judged (a review: a file hidden by its name or a set-aside
  // capture lay in a verified folder unmentioned): its contents are the station's word on nothing.
  std::vector<std::string> outside;
  entries_in(dir, &outside);
  if (!outside.empty())
    std::cout << fmt::format("note: not covered by the seal (set-aside records, temporary or hidden files; the "
                             "verdict does not rest on them): {}\n",
                             fmt::join(outside, ", "));
  if (const auto steps = pending_steps(dir))
    std::cout << (live ? fmt::format("note: the run's ending is not finished ({}: {}): a rig process holds the folder "
                                     "now (its lock)\n",
                                     kEndingPending, fmt::join(*steps, ", "))
                  : a_resume_finishes(dir, *steps)
                      ? fmt::format("note: the run's ending is not finished ({}: {}): `rig run --resume {}{}` finishes "
                                    "it\n",
                                    kEndingPending, fmt::join(*steps, ", "), shell_word(dir),
                                    seal_in(dir) ? seal_key_words(key_path) : "")
                      : fmt::format("note: the run's ending is not finished ({}: {}), and {}; what the seal vouches "
                                    "for stands as said above\n",
                                    kEndingPending, fmt::join(*steps, ", "), kNothingFinishesIt));
  return c.ok ? kExitPass : kExitFail;
}

}  // namespace

void add_verify(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("verify", "Check a run folder against the station's seal (seal.json)");
  sub->footer("Exit codes: 0 verified; 1 not verified (not sealed, another key, a file changed, missing or added "
              "after the seal, a seal that is not final, the passport not covered); 2 no key, a key that fails its "
              "checks, or DIR not a folder.");
  auto dir = std::make_shared<std::string>();
  auto key = std::make_shared<std::string>();
  sub->add_option("DIR", *dir, "Run folder")->required();
  auto* k = sub->add_option("--seal-key", *key, "The station's key (HMAC-SHA256)")->envname("RIG_SEAL_KEY");
  sub->callback([dir, key, k, &rc] { rc = do_verify(*dir, *key, k->count() > 0); });
}

}  // namespace rig::cli
