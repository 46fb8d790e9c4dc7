// The station's seal on a run folder (rig/seal, docs/seal.md), as `rig run` and `rig verify`
// use it: where the key comes from, which files a run seals when, and the checks a resume makes
// before it trusts the folder.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "rig/seal/seal.hpp"

namespace rig::cli {

// --seal-key FILE (or RIG_SEAL_KEY), else none: the station names its key itself, never the run
// folder (a run.json pointing at another hardware file must not bring its own key). Loaded and
// checked before any device opens.
std::optional<seal::Key> station_key(const std::string& option);

// The files of `dir` a seal covers: every regular file, its subfolders' included, but run.log
// (appended to after the last seal), the seals themselves, *.tmp and hidden files and folders
// (the replay's scratch) and the partial recordings a resume set aside (*.interrupted-N: what
// they hold was never checked, so the key does not vouch for it). A symbolic link anywhere is
// ConfigError: a sealed folder holds its own files.
std::vector<std::string> sealable_files(const std::string& dir);

// Seals `dir` (sealable_files); with `checkpoint_text`, checkpoint.json is sealed as that text,
// about to be written. The seal it replaces is kept as seal.prev.json until the next one, so a
// stop between the seal and the checkpoint leaves one that holds. ConfigError when it cannot be
// written (the run stops: exit 2).
void seal_run_folder(const std::string& dir, const seal::Key& k,
                     const std::optional<std::string>& checkpoint_text = std::nullopt);
// After the final seal: the previous one is no longer needed.
void drop_previous_seal(const std::string& dir);

// The outputs every ending writes again (passport.json, junit.xml, analysis.json, report.html)
// and the loop test's records, which the loop phase writes again: a resume does not need them.
bool rewritten_by_a_resume(const std::string& rel);

// Before a resume trusts `dir`, first of all (before run.json is read): with a key, seal.json or
// seal.prev.json must be this key's, hold as a list, and every file it lists that a resume reads
// (run.json, profile.toml, checkpoint.json, the captures) must be as sealed; an unsealed folder
// is refused (sealing it now would vouch for files the key never saw). Without a key a sealed
// folder is refused (a resume would leave it unsealed). Returns the files the seal that held
// lists (none without a key); ConfigError naming what does not hold.
std::vector<std::string> check_seal_before_resume(const std::string& dir, const std::optional<seal::Key>& k);

// After the checkpoint is read: a file the seal does not list must be one a stop can leave
// behind (the capture of `next_phase`, the phase the resume continues with, which the resume
// sets aside, or a file a resume writes again); anything else was added after the seal:
// ConfigError naming it.
void refuse_added_files(const std::string& dir, const std::vector<std::string>& sealed,
                        const std::string& next_phase);

}  // namespace rig::cli
