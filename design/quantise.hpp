// Rounding for the quantisers of the DUT model (its ADC and PWM timer) and of the emulated
// DUT's current-sense ADC and output words: one rule, so the loop model and the emulator
// quantise alike.
#pragma once

namespace rig::design {

// Round to nearest (ties to even) for |v| < 2^51 with two additions: no libm call,
// exact and identical on every IEEE-754 platform (the project never uses -ffast-math).
inline double round_half_even(double v) {
  constexpr double kMagic = 6755399441055744.0;  // 1.5 * 2^52
  return (v + kMagic) - kMagic;
}

}  // namespace rig::design
