// Whether a passport's outcomes are the ones its own values and limits give (README "How `rig
// run` decides"). A passport edited after the run (FAIL changed to PASS, a value moved) made
// `rig report` print a PASS report with a value outside its own limits (a review): the report and
// the history read a passport only when its verdicts hold. This is a consistency check, not the
// decision rule (rig/executive/measurement.hpp decides); `rig verify` checks a sealed run's bytes.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace rig::report {

// Empty when every value's outcome follows from its value and limits and the run's outcome from
// the values' outcomes; else the first contradiction, naming the field and the values.
std::string verdict_contradiction(const nlohmann::json& passport);

// The unit docs/contracts.md gives a measurement of every passport ("" for a name it does not
// list): a passport whose bias was edited to read "mg" was reported and recorded as a bias in mg
// (a technician's review).
std::string contract_unit(const std::string& name);

// Whether `name` is a GOST in-run B value, in_run_b_gost_<N>s (N digits: its block length in s).
bool is_gost_b(const std::string& name);

// Throws ConfigError "PATH: <the contradiction> (...)" when there is one.
void require_consistent_verdicts(const nlohmann::json& passport, const std::string& path);

}  // namespace rig::report
