// An unsealed passport held to the run that wrote it: the limits it states must be the ones its
// folder's profile.toml gives, its profile_sha256 that file's, its values the procedure's, and
// its junit.xml (staged or in place) must state its outcome and failure count. These catch edits
// by hand (a passport's FAIL made PASS with its limit loosened passes its own consistency
// checks); a seal vouches for the bytes (docs/seal.md). Used by a resume that finishes an ending,
// `rig history --record` and `rig report` on unsealed folders.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "rig/executive/measurement.hpp"

namespace rig::cli {

// "" when `passport` (dir's) agrees with its run, else what does not. `profile_sha256`: the
// digest its folder's profile.toml has (nullopt: not checked, a passport of a rig before it
// wrote one).
std::string passport_unlike_its_run(const std::string& dir, const nlohmann::json& passport,
                                    const MeasurementSet& declared, const std::optional<std::string>& profile_sha256);

// The same against dir's own profile.toml (its limits and digest; the digest only where the
// passport states one). "" also where the folder has no profile.toml (a folder of a rig before
// it kept one: nothing to hold it to). A profile.toml that cannot be read is ConfigError.
std::string passport_unlike_its_folder(const std::string& dir, const nlohmann::json& passport);

}  // namespace rig::cli
