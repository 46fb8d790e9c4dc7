// The run's outputs for people and machines: passport.json (docs/contracts.md
// shape, rig.passport/1) and junit.xml (one testcase per measurement).
#pragma once
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "rig/executive/executive.hpp"
#include "rig/executive/measurement.hpp"

namespace rig {

struct PassportInfo {
  std::string serial, profile, plant, station, started, finished, software, out_dir;
  // SHA-256 of profile.toml, the profile's text the run was judged by (empty: not written).
  std::string profile_sha256;
  std::vector<std::string> captures;  // relative to out_dir
  // Procedure steps the DUT could not take (step, why): "skipped" in passport.json, only when any.
  std::vector<std::pair<std::string, std::string>> skipped;
};

nlohmann::ordered_json make_passport(const PassportInfo& info, const RunResult& result, const MeasurementSet& values);
// passport.json's text (two-space indent, a final newline).
std::string passport_text(const nlohmann::ordered_json& passport);
std::string junit_xml(const PassportInfo& info, const RunResult& result, const MeasurementSet& values);
// A fixed-width pass/fail table for the terminal.
std::string passport_table(const nlohmann::ordered_json& passport);
// The line after an emulated run's OUTCOME line (its passport passes under whatever serial was typed).
inline constexpr const char* kEmulatedPlantLine = "(emulated plant: a simulated DUT, not a device on the bench)\n";

}  // namespace rig
