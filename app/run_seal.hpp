// The station's seal on a run folder (rig/seal, docs/seal.md), as `rig run` and `rig verify`
// use it: where the key comes from, which files a run seals when, and the check a resume makes
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

// Seals every file in `dir` (its subfolders included) but run.log (appended to after the last
// seal), the seals themselves, temporary files and hidden folders (the replay's scratch); with
// `checkpoint_text`, checkpoint.json is sealed as that text, about to be written. The seal it
// replaces is kept as seal.prev.json until the next one, so a stop between the seal and the
// checkpoint leaves one that holds.
void seal_run_folder(const std::string& dir, const seal::Key& k,
                     const std::optional<std::string>& checkpoint_text = std::nullopt);
// After the final seal: the previous one is no longer needed.
void drop_previous_seal(const std::string& dir);

// Before a resume trusts `dir`: with a key, seal.json or seal.prev.json must hold and cover
// run.json, profile.toml and checkpoint.json (where present); without one, a sealed folder is
// refused (a resume would leave it unsealed). ConfigError naming what does not hold.
void check_seal_before_resume(const std::string& dir, const std::optional<seal::Key>& k);

}  // namespace rig::cli
