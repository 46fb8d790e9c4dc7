// Measurements with units, limits and outcomes (the passport's values),
// in the manner of OpenHTF's measurements: a value is judged against the
// profile's limits where it has them; no value or no limits gives UNSET.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace rig {

enum class Outcome { Pass, Fail, Unset };
const char* to_string(Outcome o);

struct Measurement {
  std::string name;
  std::string unit;
  std::optional<double> value;
  std::optional<double> lo, hi;                          // confidence bounds, where the value has them
  std::optional<std::pair<double, double>> limits;       // [min, max] from the profile
  Outcome outcome = Outcome::Unset;
  std::string reason;                                    // why null, or the class name, or the failure
};

// Sets `outcome` (and a reason on failure) from value and limits.
void judge(Measurement& m);

nlohmann::ordered_json to_json(const Measurement& m);
Measurement measurement_from_json(const std::string& name, const nlohmann::json& j);

// Ordered set: the passport lists values in the order they were defined.
class MeasurementSet {
 public:
  // Declares a measurement (name, unit, limits) before it has a value.
  void declare(const std::string& name, const std::string& unit,
               std::optional<std::pair<double, double>> limits = std::nullopt);
  // Records a value (judged at once). Unknown names are declared on the fly.
  Measurement& set(const std::string& name, std::optional<double> value, const std::string& reason = {},
                   std::optional<double> lo = std::nullopt, std::optional<double> hi = std::nullopt);
  const Measurement* find(const std::string& name) const;
  Measurement* find(const std::string& name);
  const std::vector<Measurement>& all() const { return items_; }
  bool any_failed() const;
  nlohmann::ordered_json to_json() const;  // {"name": {...}, ...} in definition order
  void restore(const nlohmann::json& values);  // from to_json() (resume)

 private:
  std::vector<Measurement> items_;
};

}  // namespace rig
