#include "rig/executive/measurement.hpp"

#include <cmath>
#include <sstream>

namespace rig {

const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::Pass: return "PASS";
    case Outcome::Fail: return "FAIL";
    case Outcome::Unset: return "UNSET";
  }
  return "UNSET";
}

void judge(Measurement& m) {
  if (!m.value || !std::isfinite(*m.value) || !m.limits) {
    m.outcome = Outcome::Unset;
    return;
  }
  const auto [lo, hi] = *m.limits;
  if (*m.value >= lo && *m.value <= hi) {
    m.outcome = Outcome::Pass;
  } else {
    m.outcome = Outcome::Fail;
    if (m.reason.empty()) {
      std::ostringstream os;
      os.precision(6);
      os << "value " << *m.value << " outside limits [" << lo << ", " << hi << "]";
      m.reason = os.str();
    }
  }
}

namespace {
nlohmann::ordered_json opt(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}
std::optional<double> opt_from(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || j[key].is_null()) return std::nullopt;
  return j[key].get<double>();
}
}  // namespace

nlohmann::ordered_json to_json(const Measurement& m) {
  nlohmann::ordered_json j{{"value", opt(m.value)}, {"unit", m.unit}, {"lo", opt(m.lo)}, {"hi", opt(m.hi)},
                   {"limits", nullptr}, {"outcome", to_string(m.outcome)}, {"reason", m.reason}};
  if (m.limits) j["limits"] = {m.limits->first, m.limits->second};
  return j;
}

Measurement measurement_from_json(const std::string& name, const nlohmann::json& j) {
  Measurement m;
  m.name = name;
  m.unit = j.value("unit", "");
  m.value = opt_from(j, "value");
  m.lo = opt_from(j, "lo");
  m.hi = opt_from(j, "hi");
  if (j.contains("limits") && j["limits"].is_array() && j["limits"].size() == 2)
    m.limits = std::make_pair(j["limits"][0].get<double>(), j["limits"][1].get<double>());
  const std::string o = j.value("outcome", "UNSET");
  m.outcome = o == "PASS" ? Outcome::Pass : o == "FAIL" ? Outcome::Fail : Outcome::Unset;
  m.reason = j.value("reason", "");
  return m;
}

void MeasurementSet::declare(const std::string& name, const std::string& unit,
                             std::optional<std::pair<double, double>> limits) {
  if (Measurement* m = find(name)) {
    m->unit = unit;
    m->limits = limits;
    return;
  }
  Measurement m;
  m.name = name;
  m.unit = unit;
  m.limits = limits;
  m.reason = "not measured";
  items_.push_back(m);
}

Measurement& MeasurementSet::set(const std::string& name, std::optional<double> value, const std::string& reason,
                                 std::optional<double> lo, std::optional<double> hi) {
  Measurement* m = find(name);
  if (!m) {
    declare(name, "");
    m = &items_.back();
  }
  m->value = value;
  m->lo = lo;
  m->hi = hi;
  m->reason = reason;
  judge(*m);
  return *m;
}

const Measurement* MeasurementSet::find(const std::string& name) const {
  for (const auto& m : items_)
    if (m.name == name) return &m;
  return nullptr;
}
Measurement* MeasurementSet::find(const std::string& name) {
  for (auto& m : items_)
    if (m.name == name) return &m;
  return nullptr;
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
  for (auto it = values.begin(); it != values.end(); ++it) {
    Measurement m = measurement_from_json(it.key(), it.value());
    if (Measurement* cur = find(it.key())) {
      const auto limits = cur->limits;  // limits come from the current profile
      *cur = m;
      cur->limits = limits;
      judge(*cur);
    } else {
      items_.push_back(m);
    }
  }
}

}  // namespace rig
