#include "rig/executive/passport.hpp"

#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "rig/core/markup.hpp"

namespace rig {

nlohmann::ordered_json make_passport(const PassportInfo& info, const RunResult& result, const MeasurementSet& values) {
  nlohmann::ordered_json p;
  p["schema"] = "rig.passport/1";
  p["serial"] = info.serial;
  p["profile"] = info.profile;
  if (!info.profile_sha256.empty()) p["profile_sha256"] = info.profile_sha256;
  p["plant"] = info.plant;
  p["station"] = info.station;
  p["started"] = info.started;
  p["finished"] = info.finished;
  p["outcome"] = to_string(result.outcome);
  p["values"] = values.to_json();
  p["software"] = info.software;
  p["out_dir"] = info.out_dir;
  p["captures"] = info.captures;
  if (!info.skipped.empty()) {
    nlohmann::ordered_json sk = nlohmann::ordered_json::array();
    for (const auto& [step, why] : info.skipped) sk.push_back({{"step", step}, {"reason", why}});
    p["skipped"] = sk;
  }
  nlohmann::ordered_json phases = nlohmann::ordered_json::array();
  for (const auto& r : result.phases)
    phases.push_back({{"id", r.id}, {"title", r.title}, {"status", r.status}, {"started", r.started},
                      {"finished", r.finished}, {"message", r.message}});
  p["phases"] = phases;
  if (result.outcome == RunOutcome::Aborted || result.outcome == RunOutcome::Error)
    p["aborted_reason"] = result.message;
  return p;
}

std::string passport_text(const nlohmann::ordered_json& passport) { return passport.dump(2) + "\n"; }

namespace {
std::string xml_escape(const std::string& s) { return markup_escape(s); }
std::string num(const std::optional<double>& v) { return v ? fmt::format("{:.6g}", *v) : "null"; }
}  // namespace

std::string junit_xml(const PassportInfo& info, const RunResult& result, const MeasurementSet& values) {
  std::size_t failures = 0, skipped = 0;
  for (const auto& m : values.all()) {
    failures += m.outcome == Outcome::Fail;
    skipped += m.outcome == Outcome::Unset;
  }
  const bool aborted = result.outcome == RunOutcome::Aborted || result.outcome == RunOutcome::Error;
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  o << "<testsuites name=\"rig\" tests=\"" << values.all().size() + (aborted ? 1 : 0) << "\" failures=\"" << failures
    << "\" errors=\"" << (aborted ? 1 : 0) << "\">\n";
  o << "  <testsuite name=\"" << xml_escape("acceptance." + info.profile) << "\" tests=\""
    << values.all().size() + (aborted ? 1 : 0) << "\" failures=\"" << failures << "\" errors=\"" << (aborted ? 1 : 0)
    << "\" skipped=\"" << skipped << "\" timestamp=\"" << xml_escape(info.started) << "\">\n";
  o << "    <properties><property name=\"serial\" value=\"" << xml_escape(info.serial)
    << "\"/><property name=\"profile\" value=\"" << xml_escape(info.profile)
    << (info.profile_sha256.empty() ? std::string()
                                    : "\"/><property name=\"profile_sha256\" value=\"" + info.profile_sha256)
    << "\"/><property name=\"plant\" value=\"" << xml_escape(info.plant) << "\"/><property name=\"outcome\" value=\""
    << to_string(result.outcome) << "\"/>";
  // The steps the DUT could not take (passport.json `skipped`), one property each: a CI system
  // reading junit.xml alone saw a clean pass whose output filter was never loaded (a review).
  for (const auto& [step, why] : info.skipped)
    o << "<property name=\"skipped_step\" value=\"" << xml_escape(step + ": " + why) << "\"/>";
  o << "</properties>\n";
  for (const auto& m : values.all()) {
    o << "    <testcase classname=\"passport\" name=\"" << xml_escape(m.name) << "\">";
    std::string lim = m.limits ? fmt::format("[{:.6g}, {:.6g}]", m.limits->first, m.limits->second) : "none";
    std::string value = num(m.value);
    if (m.outcome == Outcome::Fail && m.value && m.limits) {  // the digits that put it outside
      const ShownOutside so = shown_outside(*m.value, m.limits->first, m.limits->second);
      value = so.value, lim = "[" + so.lo + ", " + so.hi + "]";
    }
    if (m.outcome == Outcome::Fail) {
      // `value` and `lim` are already shown with the digits that put the value outside.
      const std::string what = m.value ? fmt::format("{} = {} {} outside limits {}", m.name, value, m.unit, lim)
                                       : !m.null_verdict.empty() ? fmt::format("{}: {}", m.name, m.null_verdict)
                                       : m.limits ? fmt::format("{} is required (limits {}) but has no value", m.name, lim)
                                                  : fmt::format("{} is required but has no value", m.name);  // a class table
      o << "<failure message=\"" << xml_escape(what) << "\">" << xml_escape(m.shown_reason()) << "</failure>";
    } else if (m.outcome == Outcome::Unset) {
      o << "<skipped message=\"" << xml_escape(m.value ? "no limits: " + num(m.value) + " " + m.unit : m.reason)
        << "\"/>";
    }
    o << "<system-out>" << xml_escape(fmt::format("value={} unit={} limits={} {}", value, m.unit, lim, m.shown_reason()))
      << "</system-out></testcase>\n";
  }
  if (aborted)
    o << "    <testcase classname=\"procedure\" name=\"run\"><error message=\"" << xml_escape(result.message)
      << "\"/></testcase>\n";
  o << "  </testsuite>\n</testsuites>\n";
  return o.str();
}

std::string passport_table(const nlohmann::ordered_json& p) {
  std::ostringstream o;
  o << fmt::format("Passport  serial {}  profile {}  plant {}\n", p.value("serial", ""), p.value("profile", ""),
                   p.value("plant", ""));
  o << fmt::format("{:<26} {:>13} {:>13} {:>13} {:<10} {:<28} {}\n", "measurement", "value", "lo", "hi", "unit",
                   "limits", "outcome");
  auto f = [](const nlohmann::ordered_json& v) { return v.is_null() ? std::string("-") : fmt::format("{:.5g}", v.get<double>()); };
  for (auto it = p["values"].begin(); it != p["values"].end(); ++it) {
    const auto& m = it.value();
    std::string lim = "-", value = f(m["value"]);
    if (m["limits"].is_array()) lim = fmt::format("[{:.3g}, {:.3g}]", m["limits"][0].get<double>(), m["limits"][1].get<double>());
    std::string out = m.value("outcome", "UNSET");
    // A failed value and its limits with the digits that put it outside (the table's short
    // forms read "0.00314 ... [0, 0.00314] FAIL": a review).
    // Any other value beside its limits likewise where the short forms put it on the wrong side
    // (a PASS read 0.0024224 beside [0, 0.00242]: a metrologist's review).
    if (m["value"].is_number() && m["limits"].is_array()) {
      const double v = m["value"].get<double>(), lo = m["limits"][0].get<double>(), hi = m["limits"][1].get<double>();
      const bool in_order =
          shown_in_order({value, fmt::format("{:.3g}", lo), fmt::format("{:.3g}", hi)}, v, lo, hi);
      if (out == "FAIL" || !in_order) {
        const ShownOutside so = shown_against_limits(v, lo, hi);
        value = so.value, lim = "[" + so.lo + ", " + so.hi + "]";
      }
    }
    const std::string reason = m.value("reason", "");
    if (!reason.empty() && (out != "PASS" || m["value"].is_null() || it.key() == "accuracy_class")) out += "  " + reason;
    o << fmt::format("{:<26} {:>13} {:>13} {:>13} {:<10} {:<28} {}\n", it.key(), value, f(m["lo"]), f(m["hi"]),
                     m.value("unit", ""), lim, out);
  }
  // The steps the DUT could not take (passport.json `skipped`), as report.html lists them.
  if (p.contains("skipped") && p["skipped"].is_array())
    for (const auto& k : p["skipped"])
      if (k.is_object()) o << "skipped: " << k.value("step", "") << ": " << k.value("reason", "") << "\n";
  o << "OUTCOME: " << p.value("outcome", "") << "\n";
  // The emulated plant's passport passes under whatever serial was typed: never read as a DUT's
  // (on a line of its own: scripts match "OUTCOME: PASS" as the whole line).
  if (p.value("plant", "") == "emulated") o << kEmulatedPlantLine;
  if (p.contains("aborted_reason")) o << "reason: " << p["aborted_reason"].get<std::string>() << "\n";
  return o.str();
}

}  // namespace rig
