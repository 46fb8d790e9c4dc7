// Model-based choice of the output filter W_f(z) (docs/method.md, the paper's two criteria):
//  1. RMS error of the output -> min, on emulated output (or a recording at the loop rate);
//  2. closed-loop bandwidth at the 0.5 level -> f_req and settling time -> min, from the
//     DUT's closed-loop model with that filter (loop_figures).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "rig/core/dut_link.hpp"

namespace rig::plant {

struct FilterCandidate {
  std::string name;          // "paper", "none", "butter2@500" ...
  FilterConfig filter;
  double bandwidth_0p5_hz = 0;
  double settling_time_s = 0;  // with settled false: a lower bound (not settled in the model's longest step)
  bool settled = true;
  double step_window_s = 0;  // the model's step it was read from (LoopFigures::step_window_s)
  double rms_g = 0;          // criterion 1: RMS of y about its mean
  bool meets_band = false;   // |bandwidth - f_req| <= band_tol * f_req
  int rank = 0;              // 1 = best
};

struct FilterSelectOptions {
  double f_req_hz = 500;
  double band_tol = 0.05;
  std::vector<int> orders{1, 2, 3, 4};
  double fc_min_hz = 300, fc_max_hz = 1500, fc_step_hz = 50;
  bool include_paper = true, include_none = true;
  double rms_seconds = 60;       // emulated output per candidate (the same noise for all)
  uint64_t seed = 1;
  // Criterion 1 on a recording of x at the DUT's loop rate instead of emulated output.
  const std::vector<double>* recorded_x = nullptr;
  // What errors call the DUT overrides' table (load_dut_params): "" for a DUT file read whole.
  std::string dut_section = "plant.dut";
};

// The cut-offs the options' range gives (min + i step up to max), checked; those at or above half
// the DUT's loop rate are not candidates (select_filters leaves them out, and refuses a range
// with none below it).
std::vector<double> candidate_cutoffs(const FilterSelectOptions& opt);

// Evaluates every candidate; returned best first (meeting the band: lowest RMS, then
// shortest settling, a lower bound after every settled time; the rest by distance of their bandwidth from f_req).
std::vector<FilterCandidate> select_filters(const toml::table* dut_cfg, const FilterSelectOptions& opt);

// Parses "paper", "none" or "butterN@FC" (e.g. butter2@500) at `rate_hz`; throws ConfigError.
FilterConfig filter_by_name(const std::string& name, double rate_hz);

}  // namespace rig::plant
