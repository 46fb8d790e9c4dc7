#include "app/passport_held.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/profile.hpp"
#include "procedures/acceptance/state.hpp"
#include "rig/seal/seal.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

namespace {
std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

std::string passport_unlike_its_run(const std::string& dir, const nlohmann::json& passport,
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
  // junit.xml states the same verdict: staged beside the passport, or already in place.
  std::error_code ec;
  const bool staged = fs::is_regular_file(dir + "/junit.xml.tmp", ec);
  if (!staged && !fs::is_regular_file(dir + "/junit.xml", ec)) return "no junit.xml beside it, staged or in place";
  const std::string junit = file_text(dir + (staged ? "/junit.xml.tmp" : "/junit.xml"));
  const std::string outcome = passport.value("outcome", "");
  const std::string which = staged ? "the junit.xml staged with it" : "junit.xml";
  if (junit.find("<property name=\"outcome\" value=\"" + outcome + "\"/>") == std::string::npos)
    return "its outcome is " + outcome + ", but " + which + " states another";
  if (junit.find("<testsuite name=") == std::string::npos ||
      junit.find("failures=\"" + std::to_string(failed) + "\"", junit.find("<testsuite name=")) == std::string::npos)
    return fmt::format("{} values FAIL in it, but {} counts other failures", failed, which);
  return "";
}

std::string passport_unlike_its_folder(const std::string& dir, const nlohmann::json& passport) {
  const std::string path = dir + "/profile.toml";
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return "";
  std::string source;
  const toml::table t = acceptance::load_profile_table(path, source);
  const acceptance::Profile p = acceptance::parse_profile(t, source);
  // The phases only for the measures they declare: no timing or DUT needed for that.
  acceptance::ProcedureState state(p);
  MeasurementSet declared;
  acceptance::declare_values(p, acceptance::build_phases(p, state), declared);
  std::optional<std::string> digest;
  if (passport.contains("profile_sha256")) digest = seal::sha256_hex(file_text(path));
  return passport_unlike_its_run(dir, passport, declared, digest);
}

}  // namespace rig::cli
