// The output filter W_f(z) as the DUT runs it: a cascade of second-order sections at the
// DUT's loop rate. Plain data shared by the device seam (rig/core/dut_link.hpp, the CAN
// link) and the design math (design/filter.hpp), so neither includes the other; kept in
// namespace rig because the seam's interface speaks it.
#pragma once
#include <vector>

namespace rig {

// One second-order IIR section: H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2).
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};
struct FilterConfig {
  std::vector<Biquad> sections;  // cascaded, at the DUT's inner loop rate
  double rate_hz = 10000.0;      // the rate the filter runs at inside the DUT
  bool enabled = true;
};

}  // namespace rig
