#pragma once
// Where a run folder keeps that its run.log is missing lines the disk refused: a key of its
// checkpoint.json (the executive writes it; rig run, rig verify, rig report and rig history read
// it). A run whose log is short has no resume: its ending would give a verdict beside a hole in the
// run's account (README, "a verdict stands on its records").

#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace rig {

inline constexpr const char* kLogMissingLinesKey = "log_missing_lines";

// What `dir`'s checkpoint records its log is missing ("run.log is missing lines: the disk refused
// N line(s), ..."); "" where it records nothing, or there is no readable checkpoint.
inline std::string checkpoint_log_missing_lines(const std::string& dir) {
  std::ifstream in(dir + "/checkpoint.json");
  if (!in) return "";
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_object() && j.contains(kLogMissingLinesKey) && j[kLogMissingLinesKey].is_string()
             ? j[kLogMissingLinesKey].get<std::string>()
             : "";
}

}  // namespace rig
