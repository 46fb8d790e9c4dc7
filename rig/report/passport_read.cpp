#include "rig/report/passport_read.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/json_unique.hpp"
#include "rig/core/log_loss.hpp"
#include "rig/core/path_kind.hpp"
#include "rig/report/passport_check.hpp"
#include "rig/report/timefmt.hpp"

namespace rig::report {

namespace {

using nlohmann::json;

// "LINE:COL" of byte `at` of `text`, both from 1.
std::string position(const std::string& text, std::size_t at) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < at && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return std::to_string(line) + ":" + std::to_string(col);
}

bool one_of(const json& v, std::initializer_list<const char*> names) {
  if (!v.is_string()) return false;
  for (const char* n : names)
    if (v.get<std::string>() == n) return true;
  return false;
}

// A field's value as the message shows it: JSON text, control bytes as \xNN.
std::string shown(const json& v) { return shown_text(v.dump()); }

void check_value(const std::string& name, const json& m, const std::string& path) {
  const std::string at = path + ": values." + name;
  if (!m.is_object()) throw ConfigError(at + ": a measurement must be an object, not " + shown(m));
  for (const char* key : {"value", "lo", "hi"})
    if (m.contains(key) && !m[key].is_number() && !m[key].is_null())
      throw ConfigError(at + "." + key + ": a number or null, not " + shown(m[key]));
  if (!m.contains("outcome") || !one_of(m["outcome"], {"PASS", "FAIL", "UNSET"}))
    throw ConfigError(at + ".outcome: PASS, FAIL or UNSET, not " + (m.contains("outcome") ? shown(m["outcome"]) : "absent"));
  if (m.contains("limits") && !m["limits"].is_null()) {
    const json& l = m["limits"];
    const bool ok = l.is_array() && l.size() == 2 && (l[0].is_number() || l[0].is_null()) &&
                    (l[1].is_number() || l[1].is_null());
    if (!ok) throw ConfigError(at + ".limits: [min, max] (numbers, null for an open end) or null, not " + shown(l));
  }
  for (const char* key : {"unit", "reason", "description"})
    if (m.contains(key) && !m[key].is_string() && !m[key].is_null())
      throw ConfigError(at + "." + key + ": a string, not " + shown(m[key]));
  // Absent or null too: rig writes every listed measurement with its unit (a re-test: a deleted
  // unit was recorded as a blank one, its runs apart from the others in `rig history --value`).
  if (const std::string unit = contract_unit(name);
      !unit.empty() && (!m.contains("unit") || !m["unit"].is_string() || m["unit"].get<std::string>() != unit))
    throw ConfigError(at + ".unit: " + (m.contains("unit") ? shown(m["unit"]) : std::string("absent")) + ", but " + name +
                      " is in " + unit + " (docs/contracts.md): the passport was changed after the run");
}

}  // namespace

json parse_json_text(const std::string& text, const std::string& path) {
  try {
    return parse_json_unique_keys<json>(text);  // a repeated "outcome" drew its last (a review)
  } catch (const RepeatedJsonKey& e) {
    throw ConfigError(path + ": " + e.what());
  } catch (const json::parse_error& e) {
    // nlohmann's message carries "at line L, column C" already.
    throw ConfigError(path + ": malformed JSON: " + e.what());
  } catch (const json::out_of_range& e) {
    // "number overflow parsing '1e400'": the first such token in the text is the one.
    std::string what = e.what();
    const std::size_t q = what.find('\''), q2 = what.rfind('\'');
    std::string where;
    if (q != std::string::npos && q2 > q) {
      const std::size_t at = text.find(what.substr(q + 1, q2 - q - 1));
      if (at != std::string::npos) where = position(text, at) + ": ";
      what = "the number " + what.substr(q + 1, q2 - q - 1) + " is beyond the range of a double";
    }
    throw ConfigError(path + ":" + where + what);
  } catch (const json::exception& e) {
    throw ConfigError(path + ": malformed JSON: " + e.what());
  }
}

void check_passport(const json& p, const std::string& path) {
  if (!p.is_object()) throw ConfigError(path + ": the passport is not a JSON object");
  if (p.contains("schema") &&
      (!p["schema"].is_string() || p["schema"].get<std::string>().rfind("rig.passport/1", 0) != 0))
    throw ConfigError(path + ": unsupported passport schema " + shown(p["schema"]) + " (this rig reads rig.passport/1)");
  if (!p.contains("outcome") || !one_of(p["outcome"], {"PASS", "FAIL", "ABORTED", "ERROR"}))
    throw ConfigError(path + ": outcome: PASS, FAIL, ABORTED or ERROR, not " +
                      (p.contains("outcome") ? shown(p["outcome"]) : "absent"));
  // The serial is what the history groups a DUT's runs by and the report heads its page with. It
  // is empty only in a run that stopped before the DUT said who it is (an e-stop at bring-up, a
  // GPIO chip that is not there): such a run still gets its report and its history row.
  const bool judged = one_of(p["outcome"], {"PASS", "FAIL"});
  if (!p.contains("serial") || !p["serial"].is_string() || (judged && p["serial"].get<std::string>().empty()) ||
      has_unshowable(p["serial"].get<std::string>()))
    throw ConfigError(path + ": serial: " + (judged ? "a non-empty string" : "a string") +
                      " without control characters, not " + (p.contains("serial") ? shown(p["serial"]) : "absent"));
  // Times order the history (text order is time order once normalised).
  for (const char* key : {"started", "finished"}) {
    const json v = p.value(key, json());
    const bool required = std::string(key) == "started";
    if (v.is_null() && !required) continue;
    if (!v.is_string() || !history::normalize_iso8601(v.get<std::string>()))
      throw ConfigError(path + ": " + key + ": an ISO 8601 time (2026-11-29T17:11:50Z), not " +
                        (p.contains(key) ? shown(v) : "absent"));
  }
  if (!p.contains("values") || !p["values"].is_object())
    throw ConfigError(path + ": values: an object of measurements, not " +
                      (p.contains("values") ? shown(p["values"]).substr(0, 60) : "absent"));
  for (const auto& [name, m] : p["values"].items()) check_value(name, m, path);
  if (const json c = p.value("captures", json());
      !c.is_null() && !(c.is_array() && std::all_of(c.begin(), c.end(), [](const json& x) { return x.is_string(); })))
    throw ConfigError(path + ": captures: a list of file names, not " + shown(c).substr(0, 60));
  require_consistent_verdicts(p, path);
}

namespace {
// The passport against the run's own invocation (run.json, which `rig run` writes first and a
// resume keeps): the profile, the plant, the start and a serial asked for are the run's, so a
// passport that names others was changed after the run (a review: an emulated run relabelled
// "hardware" with a station, a ci run relabelled "paper", were reported and recorded). A folder
// without a readable run.json (a passport copied alone) is not compared.
void check_against_invocation(const json& p, const std::string& run_dir, const std::string& path) {
  std::ifstream in(run_dir + "/run.json", std::ios::binary);
  if (!in) return;
  std::ostringstream text;
  text << in.rdbuf();
  const json r = json::parse(text.str(), nullptr, false);
  if (!r.is_object()) return;
  auto differs = [&](const char* key, const json& mine, const json& theirs) {
    throw ConfigError(path + ": " + key + " is " + shown(mine) + ", but the run's run.json has " + shown(theirs) +
                      " (the passport was changed after its run wrote it; `rig verify` checks a sealed run)");
  };
  for (const char* key : {"profile", "plant"})
    if (r.value(key, json()).is_string() && p.value(key, json()) != r[key]) differs(key, p.value(key, json()), r[key]);
  if (const json rs = r.value("started", json()); rs.is_string()) {
    const json ps = p.value("started", json());
    const auto a = history::normalize_iso8601(rs.get<std::string>());
    const auto b = ps.is_string() ? history::normalize_iso8601(ps.get<std::string>()) : std::nullopt;
    if (a && b && *a != *b) differs("started", ps, rs);
  }
  if (const json rs = r.value("serial", json()); rs.is_string() && !rs.get<std::string>().empty() &&
                                                 p.value("serial", json()).is_string() &&
                                                 !p["serial"].get<std::string>().empty() && p["serial"] != rs)
    differs("serial", p["serial"], rs);
  // The station of an emulated run is the emulated plant's, whatever the host.
  if (r.value("plant", json()) == "emulated" && p.contains("station") && p["station"] != "emulated plant")
    throw ConfigError(path + ": station is " + shown(p["station"]) +
                      ", but the run's run.json has plant \"emulated\", whose station is \"emulated plant\" (the "
                      "passport was changed after its run wrote it; `rig verify` checks a sealed run)");
}
}  // namespace

json read_passport(const std::string& run_dir) {
  // `rig report DIR/passport.json` read ".../passport.json/passport.json: does the run folder exist?"
  if (path_kind(run_dir, "") == PathKind::file)
    throw ConfigError(run_dir + ": a file, not a run folder (give the folder that holds passport.json)");
  const std::string path = run_dir + "/passport.json";
  switch (path_kind(path, "")) {
    case PathKind::missing:
      // A folder that is there but holds no run is named as such (a review read "does the run
      // folder exist?" for a folder that exists).
      if (path_kind(run_dir, "") == PathKind::directory) {
        // A run killed before it wrote its passport is a run to finish, not "not a run folder".
        if (path_kind(run_dir + "/run.json", "") == PathKind::file) {
          // Not where its checkpoint says its log is short: that resume is refused (a review).
          if (const std::string lost = checkpoint_log_missing_lines(run_dir); !lost.empty())
            throw ConfigError(path + ": not there: the run in " + run_dir + " stopped before its end, and its "
                              "checkpoint records that " + lost + ": no resume finishes it; start a new run");
          throw ConfigError(path + ": not there: the run in " + run_dir + " has not finished (run.json, no passport: "
                            "still running, or stopped before its end); `rig run --resume " + run_dir +
                            "` finishes a stopped one");
        }
        throw ConfigError(path + ": not there: " + run_dir + " is a folder but not a run folder (no passport.json)");
      }
      throw ConfigError(path + ": cannot read the file (does the run folder exist?)");
    case PathKind::directory: throw ConfigError(path + ": a folder, not the passport file");
    default: break;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot read the file (" + std::strerror(errno) + ")");
  std::ostringstream text;
  text << in.rdbuf();
  const json p = parse_json_text(text.str(), path);
  check_passport(p, path);
  check_against_invocation(p, run_dir, path);
  return p;
}

}  // namespace rig::report
