#include "rig/report/passport_check.hpp"

#include <algorithm>
#include <cmath>

#include "rig/core/errors.hpp"

namespace rig::report {

namespace {

using nlohmann::json;

std::string text(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

// What a value's outcome must be, from its value and limits; empty when the passport alone
// cannot tell (no limits: a class table may require it; null in a run that stopped early).
// `every_phase_ran`: an ABORTED or ERROR run whose phases are all done or skipped (a signal or a lost
// record after the last phase): its values were judged as a complete run's. (A resume that kept
// every phase and stopped in its bring-up lists them all skipped too, and judged as a stopped run:
// so here a null required value may be FAIL or UNSET, never PASS.)
std::string expected_outcome(const json& m, bool run_complete, bool every_phase_ran, std::string& why) {
  // [min, max], an open end written as null (JSON has no infinity).
  const json limits = m.value("limits", json());
  const auto end = [&](std::size_t i, double open) {
    return limits[i].is_number() ? limits[i].get<double>() : limits[i].is_null() ? open : std::nan("");
  };
  if (!limits.is_array() || limits.size() != 2) {
    // Not judged (UNSET), except a value the profile requires without limits (accuracy_class
    // with a class table; the passport does not say which): present, it passes; null, it fails a
    // complete run. So a value without limits never fails, and a null one never passes.
    const std::string got = text(m.value("outcome", json("")));
    const bool has = m.value("value", json()).is_number();
    if (has && got == "FAIL") {
      why = "it has a value and no limits (not judged: UNSET)";
      return "UNSET";
    }
    if (!has && got == "PASS") {
      why = "it has no value";
      return run_complete ? "FAIL" : "UNSET";
    }
    if (!has && got == "FAIL" && !run_complete && !every_phase_ran) {
      why = "the run stopped early (what was not measured stays UNSET)";
      return "UNSET";
    }
    return {};
  }
  const double lo = end(0, -HUGE_VAL), hi = end(1, HUGE_VAL);
  if (std::isnan(lo) || std::isnan(hi)) return {};
  const json v = m.value("value", json());
  if (!v.is_number()) {
    why = "it has limits and no value";
    return run_complete ? "FAIL" : std::string();
  }
  const double x = v.get<double>();
  const bool in = x >= lo && x <= hi;
  // json's dump: the shortest text that reads back as the same double, so "outside" is never shown
  // with digits that look inside.
  why = "its value " + v.dump() + " is " + (in ? "within" : "outside") + " its limits " + limits.dump();
  return in ? "PASS" : "FAIL";
}

// The measurements every acceptance passport lists, null when not measured, each with its unit
// (docs/contracts.md, "Measurement names"); the GOST block lengths are the profile's, at least one
// of them, each in g.
struct ListedMeasurement {
  const char* name;
  const char* unit;
};
constexpr ListedMeasurement kEveryPassportLists[] = {
    {"bias", "g"},           {"base_error", "g"},   {"in_run_b_allan", "g"}, {"tau_cp", "s"},
    {"q", "g*h"},            {"n", "g*h^0.5"},      {"k", "g/h^0.5"},        {"r", "g/h"},
    {"in_run_b_allan_filtered", "g"}, {"rms_unfiltered", "g"}, {"rms_filtered", "g"},
    {"bandwidth_0p5", "Hz"}, {"settling_time", "s"}, {"accuracy_class", "-"}};

// A judged run (PASS or FAIL) went through every phase and lists every measurement: a phase left
// pending, aborted or failed, or a value taken out, is a passport changed after its run (a review:
// a hand-edited PASS with pending phases and its failing value deleted was reported and recorded).
// The first phase neither done nor skipped (an entry that is no object is not judged here), or
// ph.size() when every one is.
std::size_t first_unfinished_phase(const json& ph) {
  for (std::size_t i = 0; i < ph.size(); ++i) {
    if (!ph[i].is_object()) continue;
    const std::string st = text(ph[i].value("status", json("")));
    if (st != "done" && st != "skipped") return i;
  }
  return ph.size();
}

std::string incomplete_judged_run(const json& p, const std::string& run) {
  // Its phases too: deleting them dodged the check (a review).
  const json ph = p.value("phases", json());
  if (!ph.is_array() || ph.empty())
    return "outcome is " + run + ", but " + (p.contains("phases") ? "phases is " + ph.dump().substr(0, 40) : "phases is absent") +
           " (a judged run lists the phases it went through)";
  if (const std::size_t i = first_unfinished_phase(ph); i < ph.size())
    return "outcome is " + run + ", but phases[" + std::to_string(i) + "] (" + text(ph[i].value("id", json(""))) + ") is " +
           text(ph[i].value("status", json(""))) + " (a judged run has done or skipped every phase)";
  const json& v = p["values"];
  for (const ListedMeasurement& listed : kEveryPassportLists)
    if (!v.contains(listed.name))
      return "outcome is " + run + ", but values has no " + listed.name +
             " (a passport lists every measurement of the procedure, null when not measured)";
  bool gost = false;
  for (const auto& [name, m] : v.items()) gost = gost || name.rfind("in_run_b_gost_", 0) == 0;
  if (!gost)
    return "outcome is " + run + ", but values has no in_run_b_gost_<N>s (a passport lists every measurement of "
           "the procedure, null when not measured)";
  return {};
}

bool every_phase_ran(const json& p) {
  const json ph = p.value("phases", json());
  return ph.is_array() && !ph.empty() && std::all_of(ph.begin(), ph.end(), [](const json& x) { return x.is_object(); }) &&
         first_unfinished_phase(ph) == ph.size();
}

}  // namespace

bool is_gost_b(const std::string& name) {
  const std::string pre = "in_run_b_gost_";
  return name.size() > pre.size() + 1 && name.compare(0, pre.size(), pre) == 0 && name.back() == 's' &&
         name.find_first_not_of("0123456789", pre.size()) == name.size() - 1;
}

std::string contract_unit(const std::string& name) {
  for (const auto& [listed, unit] : kEveryPassportLists)
    if (name == listed) return unit;
  return is_gost_b(name) ? "g" : "";  // the GOST B of N-second block means
}

std::string verdict_contradiction(const json& p) {
  if (!p.is_object() || !p.contains("values") || !p["values"].is_object()) return {};
  const std::string run = text(p.value("outcome", json("")));
  const bool complete = run == "PASS" || run == "FAIL";  // ABORTED and ERROR judge what they measured
  if (complete)
    if (std::string c = incomplete_judged_run(p, run); !c.empty()) return c;
  // The reason a run stopped comes with, and only with, a run that stopped (docs/contracts.md): a
  // FAIL relabelled ABORTED left the first-pass yield as a retest, and a PASS carried an abort's
  // reason onto its page (a review).
  const bool has_reason = !p.value("aborted_reason", json()).is_null();
  if (complete && has_reason)
    return "outcome is " + run + ", but the passport has an aborted_reason (only an ABORTED or ERROR run has one)";
  if (!complete && !has_reason)
    return "outcome is " + run + ", but the passport has no aborted_reason (an ABORTED or ERROR run says why it stopped)";
  if (const json c = p["values"].value("accuracy_class", json()); c.is_object() && c.value("value", json()).is_number()) {
    const double k = c["value"].get<double>();
    if (!(k >= 1 && k <= 1e6 && std::floor(k) == k))
      return "values.accuracy_class.value is " + c["value"].dump() + ", which is no class (a 1-based class index)";
  }
  for (const auto& [name, m] : p["values"].items()) {
    if (!m.is_object()) continue;
    const json lo = m.value("lo", json()), hi = m.value("hi", json()), v = m.value("value", json());
    if (lo.is_number() && hi.is_number() && lo.get<double>() > hi.get<double>())
      return "values." + name + ".lo " + lo.dump() + " is above its hi " + hi.dump();
    // Every interval rig writes holds its value (GOST's about the mean, chi-square and the noise
    // model's about the estimate); a value moved without its bounds does not (a review). A hair of
    // rounding is allowed.
    if (!v.is_number()) continue;
    const double x = v.get<double>();
    const double slack = 1e-9 * std::max({std::fabs(x), lo.is_number() ? std::fabs(lo.get<double>()) : 0.0,
                                          hi.is_number() ? std::fabs(hi.get<double>()) : 0.0});
    if ((lo.is_number() && x < lo.get<double>() - slack) || (hi.is_number() && x > hi.get<double>() + slack))
      return "values." + name + ".value " + v.dump() + " is outside its own bounds [" + (lo.is_number() ? lo.dump() : "null") +
             ", " + (hi.is_number() ? hi.dump() : "null") + "]";
  }
  std::string failed;  // the first value that failed
  const bool all_ran = every_phase_ran(p);
  for (const auto& [name, m] : p["values"].items()) {
    if (!m.is_object()) continue;
    const std::string got = text(m.value("outcome", json("")));
    if (got == "FAIL" && failed.empty()) failed = name;
    std::string why;
    const std::string want = expected_outcome(m, complete, all_ran, why);
    if (!want.empty() && got != want) return "values." + name + ".outcome is " + got + ", but " + why;
    if (run == "PASS" && got != "PASS" && m.value("limits", json()).is_array())
      return "outcome is PASS, but values." + name + " (limited) is " + got;
  }
  if (run == "PASS" && !failed.empty()) return "outcome is PASS, but values." + failed + " is FAIL";
  return {};
}

void require_consistent_verdicts(const json& passport, const std::string& path) {
  const std::string c = verdict_contradiction(passport);
  if (c.empty()) return;
  throw ConfigError(path + ": " + c +
                    " (not the verdict rig's rule gives: the passport was changed after its run wrote it, or a rig "
                    "before that rule wrote it; `rig verify` checks a sealed run)");
}

}  // namespace rig::report
