#include "rig/executive/measurement.hpp"

#include "rig/executive/checkpoint_keys.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>


namespace rig {

const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::Pass: return "PASS";
    case Outcome::Fail: return "FAIL";
    case Outcome::Unset: return "UNSET";
  }
  return "UNSET";
}

void judge(Measurement& m, bool run_complete) {
  m.verdict.clear();
  const bool needed = m.limits.has_value() || m.required;
  if (!m.value || !std::isfinite(*m.value)) {
    // Issue 12: an acceptance passport never passes a DUT whose limited value could not be measured.
    if (needed && run_complete) {
      m.outcome = Outcome::Fail;
      m.verdict = m.null_verdict.empty() ? "required value not measured" : m.null_verdict;
    } else {
      m.outcome = Outcome::Unset;
    }
    return;
  }
  if (!m.limits) {
    m.outcome = m.required ? Outcome::Pass : Outcome::Unset;
    return;
  }
  const auto [lo, hi] = *m.limits;
  if (*m.value >= lo && *m.value <= hi) {
    m.outcome = Outcome::Pass;
  } else {
    m.outcome = Outcome::Fail;
    if (m.reason.empty()) {  // a phase's own note (e.g. how the value was read) is kept as the reason
      const ShownOutside s = shown_outside(*m.value, lo, hi);
      m.verdict = "value " + s.value + " outside limits [" + s.lo + ", " + s.hi + "]";
    }
  }
}

std::string Measurement::shown_reason() const {
  if (verdict.empty()) return reason;
  return reason.empty() ? verdict : verdict + ": " + reason;
}

namespace {
nlohmann::ordered_json opt(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}
// number | null | absent, else an error naming the field.
std::optional<double> opt_number(const nlohmann::json& j, const std::string& where, const char* key) {
  if (!j.contains(key) || j[key].is_null()) return std::nullopt;
  if (!j[key].is_number())
    throw std::invalid_argument(where + "." + key + ": expected a number or null, found " + j[key].type_name());
  return j[key].get<double>();
}
}  // namespace

nlohmann::ordered_json to_json(const Measurement& m) {
  nlohmann::ordered_json j{{"value", opt(m.value)}, {"unit", m.unit}, {"lo", opt(m.lo)}, {"hi", opt(m.hi)},
                   {"limits", nullptr}, {"outcome", to_string(m.outcome)}, {"reason", m.shown_reason()}};
  if (m.limits) j["limits"] = {m.limits->first, m.limits->second};
  if (!m.description.empty()) j["description"] = m.description;
  // A class index is an integer (docs/contracts.md): 2, not 2.0, which a reader typed for an
  // integer (Go's encoding/json into int) refuses (an automation engineer's review).
  if (m.name == "accuracy_class" && m.value && std::isfinite(*m.value) && *m.value == std::floor(*m.value) &&
      std::abs(*m.value) < 1e9)
    j["value"] = static_cast<std::int64_t>(*m.value);
  return j;
}

void MeasurementSet::declare(const MeasurementSpec& spec, std::optional<std::pair<double, double>> limits,
                             bool required) {
  Measurement* m = find_mut(spec.name);
  if (!m) {
    items_.emplace_back();
    m = &items_.back();
    m->name = spec.name;
    m->reason = "not measured";
  }
  m->unit = spec.unit;
  m->description = spec.description;
  m->limits = limits;
  m->required = required;
}

Measurement& MeasurementSet::set(const std::string& name, std::optional<double> value, const std::string& reason,
                                 std::optional<double> lo, std::optional<double> hi) {
  Measurement* m = find_mut(name);
  if (!m) throw std::logic_error("measurement '" + name + "' was not declared by any phase");
  if (!scope_phase_.empty() && std::find(scope_.begin(), scope_.end(), name) == scope_.end())
    throw std::logic_error("phase '" + scope_phase_ + "' sets '" + name + "', which it does not declare");
  m->value = value;
  m->lo = lo;
  m->hi = hi;
  m->reason = reason;
  m->outcome = Outcome::Unset;  // judged once, by judge_all()
  m->verdict.clear();
  m->null_verdict.clear();
  return *m;
}

void MeasurementSet::note_scope(const std::string& note) {
  for (const std::string& name : scope_)
    if (Measurement* m = find_mut(name)) m->reason += (m->reason.empty() ? "" : "; ") + note;
}

void MeasurementSet::set_scope(std::string phase, std::vector<std::string> names) {
  scope_phase_ = std::move(phase);
  scope_ = std::move(names);
}

void MeasurementSet::forget(const std::string& name, const std::string& reason) {
  Measurement* m = find_mut(name);
  if (!m) throw std::logic_error("measurement '" + name + "' was never declared");
  m->value.reset();
  m->lo.reset();
  m->hi.reset();
  m->reason = reason;  // what a resume stopped before the phase ran again says
  m->verdict.clear();
  m->null_verdict.clear();
  m->outcome = Outcome::Unset;
}

const Measurement* MeasurementSet::find(const std::string& name) const {
  for (const auto& m : items_)
    if (m.name == name) return &m;
  return nullptr;
}
Measurement* MeasurementSet::find_mut(const std::string& name) {
  for (auto& m : items_)
    if (m.name == name) return &m;
  return nullptr;
}

void MeasurementSet::judge_all(bool run_complete) {
  for (auto& m : items_) judge(m, run_complete);
}

bool MeasurementSet::any_failed() const {
  for (const auto& m : items_)
    if (m.outcome == Outcome::Fail) return true;
  return false;
}

nlohmann::ordered_json MeasurementSet::to_json() const {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& m : items_) j[m.name] = rig::to_json(m);
  return j;
}

void MeasurementSet::restore(const nlohmann::json& values) {
  if (!values.is_object()) throw std::invalid_argument(std::string("values: expected an object, found ") + values.type_name());
  for (auto it = values.begin(); it != values.end(); ++it) {
    const std::string where = "values." + it.key();
    Measurement* cur = find_mut(it.key());
    if (!cur) throw std::invalid_argument(where + ": not a measurement of this procedure");
    const nlohmann::json& j = it.value();
    if (!j.is_object()) throw std::invalid_argument(where + ": expected an object, found " + j.type_name());
    // The keys to_json writes; unit, limits, outcome and description are not read back (they
    // come from the current profile), but a key no version writes means the file was edited.
    static constexpr std::string_view kKeys[] = {"value",   "unit",   "lo",     "hi",
                                                 "limits",  "outcome", "reason", "description"};
    if (const auto k = first_unknown_key(j, kKeys))
      throw std::invalid_argument(where + "." + *k + ": " + std::string(kNotACheckpointKey));
    if (!j.contains("value")) throw std::invalid_argument(where + ".value: missing");
    cur->value = opt_number(j, where, "value");
    cur->lo = opt_number(j, where, "lo");
    cur->hi = opt_number(j, where, "hi");
    if (j.contains("reason") && !j["reason"].is_string())
      throw std::invalid_argument(where + ".reason: expected a string, found " + j["reason"].type_name());
    cur->reason = j.value("reason", "");
    cur->verdict.clear();
    cur->null_verdict.clear();
    cur->outcome = Outcome::Unset;  // judged again from the value and the current profile
  }
}

}  // namespace rig
