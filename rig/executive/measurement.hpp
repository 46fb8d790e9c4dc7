// Measurements with units, limits and outcomes (the passport's values),
// in the manner of OpenHTF's measurements: each phase declares what it
// measures (name, unit, description); a value may only be set on a declared
// name. Outcomes are not set with the value: judge_all() computes every
// outcome from the values and the profile's limits in one place, at the end of
// a run and identically after a resume.
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "rig/core/number_text.hpp"  // shown_outside, for the verdicts

namespace rig {

enum class Outcome { Pass, Fail, Unset };
const char* to_string(Outcome o);

// What a phase declares it measures.
struct MeasurementSpec {
  std::string name;
  std::string unit;
  std::string description;  // one line for the passport and the report
};

struct Measurement {
  std::string name;
  std::string unit;
  std::string description;
  std::optional<double> value;
  std::optional<double> lo, hi;                          // confidence bounds, where the value has them
  std::optional<std::pair<double, double>> limits;       // [min, max] from the profile
  // The profile requires a value even without numeric limits (accuracy_class with a class table):
  // a null value fails, a value passes.
  bool required = false;
  Outcome outcome = Outcome::Unset;
  std::string reason;   // the phase's note: why null, how it was obtained, or the class name
  std::string verdict;  // set by judge() on a FAIL: why it failed (empty otherwise)
  // The verdict of a required value that is null because what it is read from lies beyond its
  // scale (accuracy_class: B measured, above every class), not because nothing was measured;
  // empty: "required value not measured". Set by the phase after set(); set() clears it.
  std::string null_verdict;
  // What the passport's "reason" shows: the verdict, with the phase's note after it.
  std::string shown_reason() const;
};

// The outcome rule, the only one (README "Exit codes"):
//   value in limits -> PASS; outside -> FAIL;
//   value null (or not finite) with limits or `required` -> FAIL when the run
//     completed (`run_complete`), UNSET when it stopped early (not measured yet);
//   value without limits -> PASS if `required`, else UNSET.
void judge(Measurement& m, bool run_complete);

nlohmann::ordered_json to_json(const Measurement& m);

// Ordered set: the passport lists values in the order they were declared.
class MeasurementSet {
 public:
  // Declares a measurement before it has a value; declaring a name twice updates it.
  void declare(const MeasurementSpec& spec, std::optional<std::pair<double, double>> limits = std::nullopt,
               bool required = false);
  // While a phase runs, the names it declared (the executive sets it; empty = no phase).
  void set_scope(std::string phase, std::vector<std::string> names);
  // Records a value. Throws std::logic_error for a name no phase declared, or one the
  // running phase did not declare.
  Measurement& set(const std::string& name, std::optional<double> value, const std::string& reason = {},
                   std::optional<double> lo = std::nullopt, std::optional<double> hi = std::nullopt);
  // Appends "; note" to the reason of every value the running phase declared (what all of
  // them share: a capture that lost samples, say).
  void note_scope(const std::string& note);
  // Back to declared-but-not-measured: no value, bounds or verdict, and `reason` (what a passport
  // written before the value is set again says of it).
  void forget(const std::string& name, const std::string& reason = "not measured");
  const Measurement* find(const std::string& name) const;
  const std::vector<Measurement>& all() const { return items_; }
  // Computes every outcome (see judge()).
  void judge_all(bool run_complete);
  bool any_failed() const;
  nlohmann::ordered_json to_json() const;  // {"name": {...}, ...} in declaration order
  // From a checkpoint's "values" (written by to_json()): only value, lo, hi and reason are
  // taken; unit, description, limits and outcome come from the current declaration. Throws
  // std::invalid_argument naming "values.NAME.FIELD" on an undeclared name or a wrong type.
  void restore(const nlohmann::json& values);

 private:
  Measurement* find_mut(const std::string& name);
  std::vector<Measurement> items_;
  std::string scope_phase_;
  std::vector<std::string> scope_;
};

}  // namespace rig
