// A run folder's passport.json as `rig report` and `rig history --record` read it: one reader,
// so both refuse the same passports (a review found `--record` storing what `rig report` refused:
// another schema, a 'values' list, an outcome "PASSED" no filter finds, a start time "yesterday"
// that sorted as the newest run). Checks the shape rig writes (docs/contracts.md) and that its
// verdicts follow from its values and limits (passport_check.hpp).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace rig::report {

// Reads and checks run_dir/passport.json. Throws ConfigError naming the file, and the line and
// column or the field, for a file that cannot be read, malformed JSON (a number too large for
// a double included), a shape rig does not write, or contradicting verdicts.
nlohmann::json read_passport(const std::string& run_dir);

// The checks alone, on a passport held in memory; `path` names it in the messages.
void check_passport(const nlohmann::json& passport, const std::string& path);

// JSON text parsed with the position of any problem: "LINE:COL: what" in the ConfigError,
// after `path`. nlohmann gives no position for a number out of a double's range (1e400): it is
// found in the text.
nlohmann::json parse_json_text(const std::string& text, const std::string& path);

}  // namespace rig::report
