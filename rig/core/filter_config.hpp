// The output filter W_f(z) as the DUT runs it: a cascade of second-order sections at the
// DUT's loop rate. Plain data: the vocabulary of the device seam (dut_link.hpp, the CAN link),
// which the design math (design/filter.hpp) builds on; here, with the seam, so that rig/core
// includes nothing from a layer above it.
#pragma once
#include <vector>

namespace rig {

// One second-order IIR section: H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2).
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};
// Poles of 1 + a1 z^-1 + a2 z^-2 strictly inside the unit circle (the stability triangle): what
// a DUT's firmware accepts as an output-filter section (docs/can-protocol.md, FILTER_COMMIT).
inline bool stable_section(const Biquad& b) { return b.a2 > -1.0 && b.a2 < 1.0 && (b.a1 < 0 ? -b.a1 : b.a1) < 1.0 + b.a2; }
struct FilterConfig {
  std::vector<Biquad> sections;  // cascaded, at the DUT's inner loop rate
  double rate_hz = 10000.0;      // the rate the filter runs at inside the DUT
  bool enabled = true;
};

}  // namespace rig
