// The DUT's closed loop as designed (docs/method.md Fig. 3): the analogue pendulum, its pick-off
// and torquer, and the digital regulator around it. The loop model (design/loop_model.hpp)
// is built from these; the emulated DUT's profile ([plant.dut.loop], [plant.dut.regulator])
// fills them.
#pragma once
#include <string_view>

#include <toml++/toml.h>

#include "rig/core/filter_config.hpp"

namespace rig::design {

// The analogue pendulum, its pick-off and torquer, and the digital loop around it.
struct LoopParams {
  double loop_rate_hz = 10000;     // regulator / ADC / PWM rate inside the DUT
  double output_rate_hz = 1000;    // rig polling rate (sample-and-hold of x, y)
  double g_local_m_s2 = 9.80665;   // local gravity (converts g to m/s^2)
  double pendulosity_kg_m = 6e-6;  // ml
  double inertia_kg_m2 = 8e-8;     // J of pendulum + coil about the hinge
  double damping_n_m_s = 7.5e-5;   // gas-film damping c
  double stiffness_n_m_rad = 2e-3; // quartz flexure spring rate k
  double angle_sensor_v_rad = 200; // K_ду (capacitive pick-off after demodulation)
  double preamp_gain = 10;         // K_пу
  int adc_bits = 16;               // ADC resolution over +-adc_range_v
  double adc_range_v = 2.5;
  double pwm_full_scale_a = 0.0156;  // K_шим: coil current at duty = 1
  int pwm_counts = 4096;             // duty resolution (timer counts per half range)
  double torquer_n_m_a = 0.04525;    // K_дм
  double coil_tau_s = 2e-5;          // L/R of the torquer coil with its driver
  int delay_steps = 1;               // computation delay of the MCU, loop periods (0 or 1)
};

// W_рег(z) = Kc * PI(z) * lead(z): PI(z) = 1 + a z/(z-1), a = 2 pi f_i T;
// lead(z) = (1 - zl z^-1)/(1 - pl z^-1), zl/pl = exp(-2 pi f T) (matched z-transform).
struct RegulatorParams {
  double gain_a_per_v = 2.3e-3;
  double integral_corner_hz = 60;
  double lead_zero_hz = 150;
  double lead_pole_hz = 1500;
};

// W_рег(z) at `rate_hz` as one biquad (the form the MCU runs), input V, output A.
Biquad regulator_biquad(const RegulatorParams& r, double rate_hz);

// Read a loop / regulator table onto `p` (keys absent keep their value). `ctx` names the
// table in errors (e.g. "plant.dut.loop"); unknown keys and values out of range throw
// ConfigError with file:line:col.
void read_loop_params(const toml::table& t, std::string_view ctx, LoopParams& p);
void read_regulator_params(const toml::table& t, std::string_view ctx, RegulatorParams& p);

}  // namespace rig::design
