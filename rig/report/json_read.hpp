// Tolerant reads of the run folder's JSON for the report's pages and plots: a missing key, a
// wrong type or null gives "absent" (nullptr, NaN, "", an empty vector), never an exception,
// so a partial or damaged analysis.json still draws what it holds.
#pragma once
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rig::report {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Walks a path of keys; nullptr when any step is absent or not an object.
inline const nlohmann::json* get(const nlohmann::json& j, std::initializer_list<const char*> path) {
  const nlohmann::json* cur = &j;
  for (const char* k : path) {
    if (!cur->is_object()) return nullptr;
    auto it = cur->find(k);
    if (it == cur->end()) return nullptr;
    cur = &*it;
  }
  return cur;
}

inline double number(const nlohmann::json* j) { return j && j->is_number() ? j->get<double>() : kNaN; }
inline double number(const nlohmann::json& j, const char* key) { return number(get(j, {key})); }

// A string as it is, any other value as JSON text, "" when absent or null.
inline std::string text(const nlohmann::json* j) {
  if (!j || j->is_null()) return "";
  return j->is_string() ? j->get<std::string>() : j->dump();
}
inline std::string text(const nlohmann::json& j, const char* key) { return text(get(j, {key})); }

// A JSON array of numbers (null -> NaN); empty when absent.
inline std::vector<double> numbers(const nlohmann::json* j) {
  std::vector<double> out;
  if (!j || !j->is_array()) return out;
  out.reserve(j->size());
  for (const nlohmann::json& v : *j) out.push_back(v.is_number() ? v.get<double>() : kNaN);
  return out;
}

}  // namespace rig::report
