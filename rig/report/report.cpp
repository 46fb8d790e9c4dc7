#include "rig/report/report.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rig/core/errors.hpp"
#include "rig/report/passport_check.hpp"
#include "rig/report/report_parts.hpp"
#include "rig/report/svg.hpp"

namespace rig::report {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Reads a JSON file; `required` decides whether a problem throws or is returned.
json read_json(const fs::path& path, bool required, std::string& problem) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    problem = path.filename().string() + " is missing";
    if (required) throw ConfigError(path.string() + ": cannot read the file (does the run folder exist?)");
    return json();
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  try {
    return json::parse(ss.str());
  } catch (const json::parse_error& e) {
    // nlohmann's message already carries "at line L, column C".
    problem = path.filename().string() + " is malformed: " + e.what();
    if (required) throw ConfigError(path.string() + ": malformed JSON: " + e.what());
    return json();
  }
}

void check_passport(const json& p, const fs::path& path) {
  if (!p.is_object()) throw ConfigError(path.string() + ": the passport is not a JSON object");
  if (p.contains("schema")) {
    if (!p["schema"].is_string() || p["schema"].get<std::string>().rfind("rig.passport/1", 0) != 0)
      throw ConfigError(path.string() + ": unsupported passport schema " + p["schema"].dump() +
                        " (this rig reads rig.passport/1)");
  }
  if (p.contains("values") && !p["values"].is_object())
    throw ConfigError(path.string() + ": 'values' must be an object of measurements");
}

}  // namespace

std::string write_report(const std::string& run_dir) {
  const fs::path dir(run_dir);
  std::string ignored, analysis_problem;
  const json passport = read_json(dir / "passport.json", true, ignored);
  check_passport(passport, dir / "passport.json");
  require_consistent_verdicts(passport, (dir / "passport.json").string());
  json analysis = read_json(dir / "analysis.json", false, analysis_problem);
  if (!analysis.is_null() && !analysis.is_object()) {
    analysis_problem = "analysis.json is not a JSON object";
    analysis = json();
  }
  const std::string html = render_report(passport, analysis, analysis_problem);

  const fs::path out = dir / "report.html", tmp = dir / "report.html.tmp";
  {
    std::error_code gone;
    fs::remove(tmp, gone);  // whatever lay there (a FIFO would stall the open, a link redirect the write)
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw ConfigError(tmp.string() + ": cannot write the report");
    f << html;
    f.flush();
    if (!f) throw ConfigError(tmp.string() + ": write failed");
  }
  std::error_code ec;
  fs::rename(tmp, out, ec);
  if (ec) throw ConfigError(out.string() + ": cannot write the report: " + ec.message());
  return out.string();
}

std::string render_report(const json& passport, const json& analysis, const std::string& analysis_problem) {
  Page page(passport, analysis, analysis_problem);
  return page.html();
}

}  // namespace rig::report
