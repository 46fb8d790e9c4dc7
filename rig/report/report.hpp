// report.html: the human-readable passport of one run, drawn from the run folder's
// passport.json (required) and analysis.json (optional, may be partial after an abort).
// One self-contained file: inline CSS and inline SVG plots, no scripts, no network.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rig::report {

// Reads run_dir/passport.json and run_dir/analysis.json, writes run_dir/report.html
// (atomically: a temp file renamed into place) and returns its path.
// Throws rig::ConfigError naming the file when passport.json is missing or malformed;
// a missing or malformed analysis.json is reported inside the page, not thrown. A sealed folder's
// report.html (seal.json lists it) that the page now written would change is kept, ConfigError,
// unless `over_sealed`.
std::string write_report(const std::string& run_dir, bool over_sealed = false);
// The same from the documents in memory (`rig run`, which has just made them): the page is the
// one the folder gives, without parsing analysis.json again (3.7 MB after a `paper` run: about
// 40 ms of the run's end), drawn before passport.json is in place (app/cmd_run.cpp
// write_run_outputs puts it there after the page).
std::string write_report(const std::string& run_dir, const nlohmann::json& passport, const nlohmann::json& analysis);

// The page itself, for callers that hold the documents in memory. `analysis` may be
// null (absent); `analysis_problem` says why it is absent or partial ("" if fine); `run_dir` is
// the folder the documents were read from (the page names it; the passport's `out_dir` is where
// the run wrote them, which differs for a copied folder).
// `set_aside`: files in the folder an interrupted attempt left (*.interrupted-N, relative), which
// the passport does not list (its captures are what the run recorded and judged).
std::string render_report(const nlohmann::json& passport, const nlohmann::json& analysis,
                          const std::string& analysis_problem = "", const std::string& run_dir = "",
                          const std::vector<std::string>& set_aside = {});

}  // namespace rig::report
