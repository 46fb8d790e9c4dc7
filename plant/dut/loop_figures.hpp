// Closed-loop figures of the emulated DUT with a given output filter, from the
// same model that produces its output (the paper's criterion 2, docs/method.md).
#pragma once
#include <vector>

#include <toml++/toml.h>

#include "rig/core/dut_link.hpp"

namespace rig::plant {

struct LoopFigures {
  double bandwidth_0p5_hz = 0;   // first frequency where |H_filter * H_loop| falls to 0.5
  double bandwidth_3db_hz = 0;   // ... to 1/sqrt(2)
  double settling_time_s = 0;    // 1 g step: last entry into the +-band around the final value
  double settling_band = 0.05;   // the band used (fraction of the final value)
  double overshoot = 0;          // peak over the final value, fraction
  double dc_gain = 0;
  // Curves for plots: step response of y (with filter) and x (without), and the
  // amplitude response |H| of each, at the frequencies in freq_hz.
  std::vector<double> step_t_s, step_y, step_x;
  std::vector<double> freq_hz, amp_y, amp_x;
};

// `dut_cfg` = the profile's [plant.dut] overrides (may be null), `filter` the output
// filter to evaluate (its rate is taken as the DUT's loop rate).
LoopFigures loop_figures(const toml::table* dut_cfg, const rig::FilterConfig& filter);

// Figures from a step response / amplitude curve (shared with `rig filter`).
double settling_time(const std::vector<double>& step, double dt, double band);
double bandwidth_at(const std::vector<double>& freq, const std::vector<double>& amp, double level);

}  // namespace rig::plant
