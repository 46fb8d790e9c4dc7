// The sections of report.html, each built from the passport and (optional) analysis
// documents. Kept apart from the file handling in report.cpp.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rig::report {

class Page {
 public:
  Page(const nlohmann::json& passport, const nlohmann::json& analysis, std::string analysis_problem,
       std::string run_dir = "", std::vector<std::string> set_aside = {});
  std::string html();

 private:
  std::string head() const;
  std::string identity() const;
  std::string passport_table() const;
  std::string skipped_steps() const;
  std::string signatures() const;
  std::string phases() const;
  std::string figures();
  std::string captures() const;
  std::string notices() const;

  // Figures; each adds to missing_ what it could not draw.
  std::string allan(const std::string& ch);
  std::string psd(const std::string& ch);
  std::string timeseries();
  std::string averages();
  std::string in_run();
  std::string step();
  std::string freq();

  const nlohmann::json& p_;
  const nlohmann::json& a_;
  std::string analysis_problem_;
  std::string folder_;      // the run folder the page names (the one read, or the passport's out_dir)
  std::string written_at_;  // the passport's out_dir when the page was made from a copy elsewhere
  std::vector<std::string> set_aside_;  // *.interrupted-N files in it
  std::vector<std::string> missing_;
};

}  // namespace rig::report
