#include "rig/report/report.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rig/core/errors.hpp"
#include "rig/report/passport_read.hpp"
#include "rig/report/report_parts.hpp"
#include "rig/report/svg.hpp"

namespace rig::report {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// analysis.json, which may be missing, partial or malformed after an abort: what is wrong with
// it goes into `problem` and the page says so, rather than refusing the report.
json read_analysis(const fs::path& path, std::string& problem) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    problem = path.filename().string() + " is missing";
    return json();
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string name = path.filename().string();
  try {
    return parse_json_text(ss.str(), name);
  } catch (const ConfigError& e) {
    std::string why = e.what();  // "analysis.json: ..." or "analysis.json:LINE:COL: ..."
    why.erase(0, std::min(why.size(), name.size() + 1));
    why.erase(0, std::min(why.size(), why.find_first_not_of(' ')));
    problem = name + " is malformed: " + why;
    return json();
  }
}

// What interrupted attempts left in the folder (rig/core/set_aside.hpp): a reader of the report
// sees why captures/in-run-U10.cap.interrupted-1 is there (a review found it listed nowhere).
std::vector<std::string> set_aside_files(const fs::path& dir) {
  std::vector<std::string> out;
  for (const char* sub : {"", "captures"}) {
    std::error_code ec;
    for (fs::directory_iterator it(dir / sub, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (name.find(".interrupted-") != std::string::npos) out.push_back((fs::path(sub) / name).string());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The page from the documents read, written atomically: a temp file renamed into place.
// analysis.json's document that is neither absent (null) nor an object is drawn as absent, saying so.
// report.html as the folder's seal.json covers it (rig/seal): a page that would come out other
// than the sealed one (a copied folder names where it was read from; another rig's layout) is not
// written over it unless asked, since `rig verify` then names it changed (a technician's review:
// an archived run regenerated failed verification, silently).
enum class PageSeal { none, sealed, unreadable };
PageSeal page_seal(const fs::path& dir) {
  std::ifstream in(dir / "seal.json", std::ios::binary);
  if (!in) return PageSeal::none;
  std::ostringstream ss;
  ss << in.rdbuf();
  const json seal = json::parse(ss.str(), nullptr, false);
  if (!seal.is_object() || !seal.contains("files") || !seal["files"].is_object()) return PageSeal::unreadable;
  return seal["files"].contains("report.html") ? PageSeal::sealed : PageSeal::none;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string write_page(const fs::path& dir, const json& passport, const json& analysis, std::string analysis_problem,
                       bool over_sealed = true) {
  const bool usable = analysis.is_null() || analysis.is_object();
  if (!usable) analysis_problem = "analysis.json is not a JSON object";
  const json none;
  fs::path read_from = fs::absolute(dir).lexically_normal();
  if (!read_from.has_filename()) read_from = read_from.parent_path();  // "r1/"
  const std::string html =
      render_report(passport, usable ? analysis : none, analysis_problem, read_from.string(), set_aside_files(dir));

  const fs::path out = dir / "report.html", tmp = dir / "report.html.tmp";
  if (const PageSeal seal = over_sealed ? PageSeal::none : page_seal(dir);
      seal != PageSeal::none && fs::exists(out) && read_bytes(out) != html) {
    if (seal == PageSeal::unreadable)
      throw ConfigError((dir / "seal.json").string() + " cannot be read as a seal (`rig verify` says why), and the "
                        "page written now differs from " + out.string() + ": kept; `rig report --force` writes it");
    throw ConfigError((dir / "seal.json").string() + " seals " + out.string() +
                      ", and the page written now differs from it (passport.json or analysis.json changed since "
                      "the seal, the folder copied or moved, or another rig version: `rig verify` tells which): kept "
                      "as sealed; `rig report --force` writes it again, and `rig verify` then names report.html as "
                      "changed");
  }
  {
    std::error_code gone;
    fs::remove(tmp, gone);  // whatever lay there (a FIFO would stall the open, a link redirect the write)
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    // errno after a failed open or write is the C library's (std::ofstream sets no error_code):
    // "Permission denied", "No space left on device" tell the user what to mend (a review).
    if (!f) throw ConfigError(tmp.string() + ": cannot write the report (" + std::strerror(errno) + ")");
    f << html;
    f.flush();
    if (!f) {
      const std::string why = std::strerror(errno);
      f.close();
      fs::remove(tmp, gone);  // a half-written page is no report
      throw ConfigError(tmp.string() + ": write failed (" + why + ")");
    }
  }
  std::error_code ec;
  fs::rename(tmp, out, ec);
  if (ec) throw ConfigError(out.string() + ": cannot write the report: " + ec.message());
  return out.string();
}
}  // namespace

std::string write_report(const std::string& run_dir, bool over_sealed) {
  const fs::path dir(run_dir);
  std::string analysis_problem;
  const json passport = read_passport(run_dir);
  const json analysis = read_analysis(dir / "analysis.json", analysis_problem);  // sets the problem first
  return write_page(dir, passport, analysis, analysis_problem, over_sealed);
}

std::string write_report(const std::string& run_dir, const json& passport, const json& analysis) {
  return write_page(fs::path(run_dir), passport, analysis, "");
}

std::string render_report(const json& passport, const json& analysis, const std::string& analysis_problem,
                          const std::string& run_dir, const std::vector<std::string>& set_aside) {
  Page page(passport, analysis, analysis_problem, run_dir, set_aside);
  return page.html();
}

}  // namespace rig::report
