// A procedure profile: the method's parameters (durations, counts, order),
// the limits and the accuracy-class table. TOML; every error names file:line:column.
// Format: docs/profiles.md. The file's [plant] section belongs to the emulated plant, which
// reads it from the same table (plant/emulated/plant_config.hpp); the procedure never does.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "analysis/options.hpp"
#include "design/loop_params.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/types.hpp"

namespace rig::acceptance {

struct AccuracyClass {
  std::string name;
  double max_b_g;  // B (Russian method, of the first in_run_blocks_s length) at or below this => this class
};

struct Profile {
  std::string name;
  std::string description;
  std::string source;   // file path or "builtin:NAME"
  std::string digest;   // of the resolved profile text: a resume must use the same profile

  // [procedure]
  double rate_hz = 1000.0;
  std::vector<Orientation> order;  // the bias/base-error runs, in order
  double run_s = 100;
  double settle_s = 10;
  double in_run_s = 1800;
  Orientation in_run_orientation = Orientation::U10;
  std::vector<double> in_run_blocks_s{100, 200};
  double raw_s = 3600;
  Orientation raw_orientation = Orientation::U10;
  uint64_t max_lost_samples = 0;  // per capture; more fails the phase (or retries it)
  int retries = 0;                // capture retries on a gap beyond the limit

  // [table]
  double u10_deg = 0.0;
  double u20_deg = 180.0;

  // [filter]: the output filter the DUT is configured with before recording
  FilterConfig filter;
  std::string filter_name;

  // [loop]: the loop test on the DUT (criterion 2 measured, docs/can-protocol.md "Loop test")
  double loop_amplitude_g = 1.0;  // docs/method.md quotes the settling time for a 1 g step
  int loop_steps = 5;             // their scatter gives the figures' 95 % intervals
  double loop_record_s = 0.1;     // per step
  // Not from the profile: the hardware file's [dut.design], the DUT type's loop as its
  // manufacturer documents it (read_design_model, loop_phase.hpp). Without a loop test on the
  // DUT, the loop figures are this model's, labelled "design model"; never the emulator's.
  struct DesignModel {
    design::LoopParams loop;
    design::RegulatorParams regulator;
    std::string source;  // FILE:LINE of [dut.design]
  };
  std::optional<DesignModel> design_model;

  // [analysis]: unset keys take the analysis library's defaults (analysis/options.hpp)
  std::string taus = analysis::AnalysisOptions{}.taus;
  double confidence = analysis::AnalysisOptions{}.confidence;
  // The record length the method asks for R (docs/method.md: > 50 h). R is fitted on any record
  // (analysis/noise_model.hpp); a shorter record's R says in its reason that it is shorter.
  double r_min_record_s = analysis::AnalysisOptions{}.r_min_record_s;
  // Which B the passport's in_run_b_allan (and its limit) is: "paper" (the paper's method,
  // sigma(tau_cp)/0.664) or "lsq" (the least-squares model's B). Both are in analysis.json.
  std::string b_allan = "paper";

  std::map<std::string, std::pair<double, double>> limits;  // [limits]
  std::vector<AccuracyClass> classes;                      // [[classes]], ascending max_b_g

  double planned_total_s() const;
};

// "paper", "ci" (built in) or a file path. Files may say `base = "paper"` to
// start from a built-in profile and override a few keys.
Profile load_profile(const std::string& name_or_path);
// The same profile as a TOML table, the base merged in, with its source ("builtin:NAME" or the
// path): what load_profile parses, and where the emulated plant finds its [plant] section.
toml::table load_profile_table(const std::string& name_or_path, std::string& source,
                               std::vector<std::string>* dropped_limits = nullptr);
// A profile file's table as parsed, its base merged in and its empty limits dropped (the file
// half of load_profile_table, for a caller that has parsed the file already).
toml::table resolve_profile_file(toml::table t, std::vector<std::string>* dropped_limits = nullptr);
// The GOST B blocks the profile measures without limits, with the base's limits its own
// in_run_blocks_s dropped (load_profile_table's `dropped_limits`); "" when every block has
// limits. A run prints it: those values are UNSET, never FAIL.
std::string unjudged_blocks_note(const Profile& p, const std::vector<std::string>& dropped_limits);
Profile parse_profile(const toml::table& t, const std::string& source);
// A profile file (not a built-in) that a new run starts from names itself: one built on a base
// sets [profile] name, and a built-in's name only on that profile unchanged. ConfigError naming
// the line otherwise. (A resumed run's profile.toml is not asked: it was taken when it began.)
void check_profile_names_itself(const toml::table& resolved, const std::string& source);
std::vector<std::string> builtin_profile_names();

// The passport name of GOST B for one block length: in_run_b_gost_<length>s, the length in
// seconds as written in the profile (100 -> in_run_b_gost_100s, 2 -> in_run_b_gost_2s).
std::string gost_value_name(double block_s);
// The samples `seconds` hold at the profile's rate, rounded: a recording's when its phase
// completes (lost ones are replaced by later ones: the recording runs until it has them all),
// and a GOST block's.
uint64_t planned_samples(const Profile& p, double seconds);
const std::string& builtin_profile_text(const std::string& name);  // throws ConfigError
// The method turns the DUT 180° between U10 and U20 (docs/method.md, "U10 and U20"); a
// mount's calibration moves each angle by a fraction of a degree. Angles `t` gives (a profile's
// [table], a hardware file's [procedure]) that are not 180° ± 10° apart are refused, naming
// u20_deg's place: a typo such as u20_deg = u10_deg would otherwise run the whole procedure
// in one orientation and report a base error of zero.
void check_orientation_angles(const toml::table& t, double u10_deg, double u20_deg);

}  // namespace rig::acceptance
