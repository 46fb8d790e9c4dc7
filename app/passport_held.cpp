#include "app/passport_held.hpp"

#include <algorithm>

#include <filesystem>

#include <fmt/format.h>

#include "app/run_seal.hpp"
#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/profile.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/core/file_text.hpp"
#include "rig/core/json_unique.hpp"
#include "rig/core/markup.hpp"
#include "rig/executive/executive.hpp"
#include "rig/seal/seal.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

namespace {
std::size_t occurrences(const std::string& hay, const std::string& needle) {
  std::size_t n = 0;
  for (auto p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + needle.size())) ++n;
  return n;
}

// What junit.xml (as the rig writes it: one testsuite, its properties, a <failure> per failed
// value) says against the passport; "" when it agrees. Read as elements, not as text anywhere in
// the file: a comment holding `value="PASS"` and `failures="0"` passed a search (a re-test).
std::string junit_unlike_passport(std::string junit, const nlohmann::json& passport, std::size_t failed,
                                  const std::string& which) {
  for (auto c = junit.find("<!--"); c != std::string::npos; c = junit.find("<!--", c)) {
    const auto e = junit.find("-->", c);
    junit.erase(c, e == std::string::npos ? std::string::npos : e + 3 - c);
  }
  const auto suite = junit.find("<testsuite ");
  const auto suite_end = suite == std::string::npos ? std::string::npos : junit.find('>', suite);
  if (suite_end == std::string::npos || occurrences(junit, "<testsuite ") != 1)
    return which + " is not the one testsuite the rig writes";
  const std::string tag = junit.substr(suite, suite_end - suite);
  const auto property = [&](const std::string& name, const std::string& value) {
    return occurrences(junit, "<property name=\"" + name + "\" ") == 1 &&
           junit.find("<property name=\"" + name + "\" value=\"" + markup_escape(value) + "\"/>") != std::string::npos;
  };
  const std::string outcome = passport.value("outcome", "");
  if (!property("outcome", outcome)) return "its outcome is " + outcome + ", but " + which + " states another";
  if (tag.find(" failures=\"" + std::to_string(failed) + "\"") == std::string::npos ||
      occurrences(junit, "<failure ") != failed)
    return fmt::format("{} values FAIL in it, but {} counts other failures", failed, which);
  // Whose run it is: a serial relabelled in the passport alone passed (a re-test).
  if (passport.contains("serial") && passport["serial"].is_string() &&
      !property("serial", passport["serial"].get<std::string>()))
    return "its serial is " + passport["serial"].dump() + ", but " + which + " names another DUT";
  if (passport.contains("profile_sha256") && passport["profile_sha256"].is_string() &&
      !property("profile_sha256", passport["profile_sha256"].get<std::string>()))
    return "its profile_sha256 is not the one " + which + " states";
  return "";
}

// A passport gives what its run measured. A PASS or FAIL run ran every phase and wrote its
// checkpoint after each (a checkpoint that cannot be written ends the run ERROR), so
// checkpoint.json holds every value the passport gives a number to, with the same value, bounds
// and unit (only the outcome is judged after it). A stopped run's (ERROR, ABORTED) may hold a
// value a phase set before the stop and never checkpointed: each value it states that the
// checkpoint holds is held to it, where the checkpoint is that attempt's (a later attempt's, a
// resume killed before its ending, may have measured again: a review found such an untouched
// passport called edited). "" when it holds, else what does not. Another run's passport and
// junit.xml copied into a stopped run's folder whose run started in the same second passed
// every other check (a technician's re-test); a bias edited into an ERROR passport was drawn
// into its page and history row by the resume that finished its ending (a code review).
// A verdict's checkpoint missing or unreadable: said, for a passport written beside one (its
// profile_sha256, since 2026-12-03); an older folder's is not held. `read`: the checkpoint as a
// caller has parsed it already (passport_unlike_its_folder), else read here.
// Whether `checkpoint` is a later attempt's than the stopped run's `passport`: it holds a phase
// completed that the passport does not state done (its resume went on, and was killed before its
// own ending replaced the passport).
bool later_attempts_checkpoint(const nlohmann::json& passport, const nlohmann::json& checkpoint) {
  const nlohmann::json completed = checkpoint.value("completed", nlohmann::json::array());
  const nlohmann::json phases = passport.value("phases", nlohmann::json::array());
  if (!completed.is_array() || !phases.is_array()) return false;
  for (const nlohmann::json& id : completed) {
    const bool done = std::any_of(phases.begin(), phases.end(), [&id](const nlohmann::json& ph) {
      return ph.is_object() && ph.value("id", nlohmann::json()) == id && ph.value("status", nlohmann::json()) == "done";
    });
    if (!done) return true;
  }
  return false;
}

std::string values_unlike_checkpoint(const std::string& dir, const nlohmann::json& passport,
                                     const nlohmann::json* read = nullptr) {
  const std::string outcome = passport.value("outcome", "");
  const bool verdict = is_verdict(outcome);
  if (!verdict && outcome != "ERROR" && outcome != "ABORTED") return "";
  nlohmann::json checkpoint;
  try {
    if (read) {
      checkpoint = *read;
    } else {
      const std::string at = Executive::checkpoint_path(dir);
      std::error_code ec;
      if (!fs::exists(at, ec))  // a stopped run may have stopped before its first checkpoint
        return verdict && passport.contains("profile_sha256")
                   ? "its run's checkpoint.json, which holds what the run measured, is missing"
                   : "";
      checkpoint = parse_json_unique_keys(file_text(at));
    }
  } catch (const std::exception& e) {
    return std::string("its run's checkpoint.json cannot be read (") + e.what() + ")";
  }
  if (!checkpoint.is_object() || !checkpoint.contains("values") || !checkpoint["values"].is_object())
    return "its run's checkpoint.json holds no values";
  if (!verdict && later_attempts_checkpoint(passport, checkpoint)) return "";
  const nlohmann::json& measured = checkpoint["values"];
  for (const auto& [name, v] : passport["values"].items()) {
    if (!v.is_object()) continue;  // the shape is the reader's to refuse
    const nlohmann::json value = v.value("value", nlohmann::json());
    if (!verdict && value.is_null()) continue;  // a stopped run's unmeasured value claims nothing
    if (!measured.contains(name) || !measured[name].is_object() ||
        (measured[name].value("value", nlohmann::json()).is_null() && !value.is_null())) {
      if (value.is_null() || !verdict) continue;  // not measured, and not said to be; or measured after the last checkpoint
      return "values." + name + ".value is " + value.dump() + ", but its run's checkpoint.json holds no measurement of it";
    }
    for (const char* key : {"value", "lo", "hi", "unit"})  // as far as the checkpoint states them
      if (const nlohmann::json ran = measured[name].value(key, nlohmann::json()), has = v.value(key, nlohmann::json());
          measured[name].contains(key) && ran != has)
        return fmt::format("values.{}.{} is {}, but its run measured {} (checkpoint.json)", name, key, has.dump(),
                           ran.dump());
  }
  return "";
}

// passport_unlike_its_run but its values against the checkpoint (each caller holds them last).
std::string unlike_its_limits_and_junit(const std::string& dir, const nlohmann::json& passport,
                                        const MeasurementSet& declared, const std::optional<std::string>& profile_sha256) {
  if (profile_sha256 && passport.value("profile_sha256", nlohmann::json()) != *profile_sha256)
    return fmt::format("profile_sha256 is {}, but the folder's profile.toml digests to \"{}\"",
                       passport.value("profile_sha256", nlohmann::json()).dump(), *profile_sha256);
  if (!passport.contains("values") || !passport["values"].is_object()) return "no values";
  const nlohmann::json& values = passport["values"];
  std::size_t failed = 0;
  for (const Measurement& m : declared.all()) {
    const nlohmann::json want = m.limits ? nlohmann::json::array({m.limits->first, m.limits->second}) : nlohmann::json();
    const nlohmann::json has = values.contains(m.name) && values[m.name].is_object()
                                   ? values[m.name].value("limits", nlohmann::json())
                                   : nlohmann::json();
    if (has != want)
      return fmt::format("values.{}.limits are {}, but the folder's profile.toml gives {}", m.name, has.dump(),
                         want.is_null() ? std::string("none") : want.dump());
    failed += values.contains(m.name) && values[m.name].value("outcome", "") == "FAIL";
  }
  for (const auto& [name, v] : values.items())
    if (!declared.find(name)) return "values." + name + " is no measurement of its procedure";
  // junit.xml states the same verdict: the one staged with this passport (its ending stopped
  // between the two renames: .ending-pending there, the passport itself in place), else the one
  // in place. A junit.xml.tmp beside no list, or beside a passport still staged, is not this
  // passport's (a re-test: a stray one, written by hand, stood in for junit.xml's FAIL).
  std::error_code ec;
  const bool staged = fs::is_regular_file(dir + "/junit.xml.tmp", ec) && pending_steps(dir).has_value() &&
                      !fs::exists(dir + "/passport.json.tmp", ec);
  if (!staged && !fs::is_regular_file(dir + "/junit.xml", ec)) return "no junit.xml beside it, staged or in place";
  const std::string which = staged ? "the junit.xml staged with it" : "junit.xml";
  return junit_unlike_passport(file_text(dir + (staged ? "/junit.xml.tmp" : "/junit.xml")), passport, failed, which);
}

}  // namespace

std::string passport_unlike_its_run(const std::string& dir, const nlohmann::json& passport,
                                    const MeasurementSet& declared, const std::optional<std::string>& profile_sha256) {
  if (std::string unlike = unlike_its_limits_and_junit(dir, passport, declared, profile_sha256); !unlike.empty())
    return unlike;
  return values_unlike_checkpoint(dir, passport);
}

std::string passport_unlike_its_folder(const std::string& dir, const nlohmann::json& passport) {
  const std::string path = dir + "/profile.toml";
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    // A folder of a rig before it kept one has nothing to hold the passport to; a passport that
    // names its profile's digest was written beside one (a re-test: deleting it let any edit by).
    if (passport.contains("profile_sha256") || fs::exists(dir + "/run.json", ec))
      return "the folder's profile.toml, which its run judged it by, is missing";
    return "";
  }
  std::string source;
  const toml::table t = acceptance::load_profile_table(path, source);
  const acceptance::Profile p = acceptance::parse_profile(t, source);
  // The phases only for the measures they declare: no timing or DUT needed for that.
  acceptance::ProcedureState state(p);
  MeasurementSet declared;
  acceptance::declare_values(p, acceptance::build_phases(p, state), declared);
  std::optional<std::string> digest;
  if (passport.contains("profile_sha256")) digest = seal::sha256_hex(file_text(path));
  if (std::string unlike = unlike_its_limits_and_junit(dir, passport, declared, digest); !unlike.empty()) return unlike;
  // run.json and the checkpoint name the profile its run started with (a resume holds the folder
  // to them): a profile.toml changed since is not the one the passport was judged by (helper-97's
  // re-test: the passport, profile.toml and junit.xml edited together passed). A passport that
  // names its profile's digest (written since 2026-12-03) was written beside a run.json that names
  // the profile's (since 2026-12-02): either gone is an edit too (a re-test deleted them). The
  // folder's own digest is not printed: it made such an edit pass (as a resume's refusal).
  const bool recent = passport.contains("profile_sha256");
  nlohmann::json run_json, checkpoint;  // as read here; the checkpoint for the values' check after the loop
  bool checkpoint_read = false;
  for (const std::string file : {"run.json", "checkpoint.json"}) {
    const std::string at = dir + "/" + file;
    const bool of_run = file == "run.json";
    if (!fs::exists(at, ec)) {
      if (recent && of_run) return "its run.json, which names the run's profile, is missing";
      continue;
    }
    nlohmann::json& j = of_run ? run_json : checkpoint;
    try {
      j = parse_json_unique_keys(file_text(at));
    } catch (const std::exception& e) {
      return "its " + file + " cannot be read (" + e.what() + ")";
    }
    checkpoint_read = checkpoint_read || !of_run;
    const nlohmann::json* named = nullptr;
    if (j.is_object() && of_run && j.contains("profile_digest")) named = &j["profile_digest"];
    if (j.is_object() && !of_run && j.contains("identity") && j["identity"].is_object() &&
        j["identity"].contains("profile_digest"))
      named = &j["identity"]["profile_digest"];
    if (!named) {
      if (recent && of_run) return "its run.json names no profile_digest";
      continue;
    }
    if (*named != p.digest) return file + "'s profile_digest is " + named->dump() + ", not the folder's profile.toml's";
  }
  return values_unlike_checkpoint(dir, passport, checkpoint_read ? &checkpoint : nullptr);
}

}  // namespace rig::cli
