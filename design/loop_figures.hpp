// Closed-loop figures of the DUT with a given output filter, from the loop model (the
// paper's criterion 2, docs/method.md): bandwidth at the 0.5 level and settling time of a 1 g step.
#pragma once
#include <vector>

#include "design/filter.hpp"
#include "design/loop_params.hpp"

namespace rig::design {

struct LoopFigures {
  double bandwidth_0p5_hz = 0;   // first frequency where |H_filter * H_loop| falls to 0.5
  double bandwidth_3db_hz = 0;   // ... to 1/sqrt(2)
  double settling_time_s = 0;    // 1 g step: last entry into the +-band around the final value (the DC gain)
  bool settled = true;           // false: still outside the band in the second half of the longest window
                                 // (settling_time_s then a lower bound), or the loop is unstable
  double step_window_s = 0;      // the simulated step's length (from 50 ms, doubled until it settles)
  double largest_pole = 0;       // the linear loop's largest |z| pole
  // Past |z| = 1 by more than rounding (an integrator and its zero cancelling came out at
  // 1 + 2e-14 and was called unstable, a code review): no figures, settled false, no curves.
  bool stable() const { return largest_pole <= 1 + 1e-9; }
  double settling_band = kSettlingBand;  // the band used (fraction of the final value)
  double overshoot = 0;          // peak over the final value, fraction
  double dc_gain = 0;
  // Curves for plots: step response of y (with filter) and x (without), at most 5000 points
  // of the window (every 2^k-th sample of a long one), and the amplitude response |H| of each at
  // the frequencies in freq_hz (500 a decade, from 1 Hz or lower, below the cut-off, to Nyquist).
  std::vector<double> step_t_s, step_y, step_x;
  std::vector<double> freq_hz, amp_y, amp_x;
};

// The loop `lp` with regulator `rp` followed by `filter` (run at the loop rate, whatever its rate_hz).
LoopFigures loop_figures(const LoopParams& lp, const RegulatorParams& rp, const FilterConfig& filter);

}  // namespace rig::design
