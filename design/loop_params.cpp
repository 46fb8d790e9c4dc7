#include "design/loop_params.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>

#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::design {

Biquad regulator_biquad(const RegulatorParams& rp, double rate_hz) {
  // W_рег(z) = Kc (1 + a z/(z-1)) (1 - zl z^-1)/(1 - pl z^-1)
  //          = Kc ((1+a) - z^-1)(1 - zl z^-1) / ((1 - z^-1)(1 - pl z^-1)).
  const double T = 1.0 / rate_hz;
  const double a = 2 * std::numbers::pi * rp.integral_corner_hz * T;
  const double zl = std::exp(-2 * std::numbers::pi * rp.lead_zero_hz * T);
  const double pl = std::exp(-2 * std::numbers::pi * rp.lead_pole_hz * T);
  const double kc = rp.gain_a_per_v;
  if (rp.integral_corner_hz > 0) return {kc * (1 + a), kc * (-(1 + a) * zl - 1), kc * zl, -(1 + pl), pl};
  return {kc, -kc * zl, 0, -pl, 0};  // no integrator: the (1 - z^-1) factors cancel
}

void read_loop_params(const toml::table& t, std::string_view ctx, LoopParams& p) {
  using cfg::get_int;
  using cfg::get_number;
  cfg::check_keys(t,
                  {"loop_rate_hz", "output_rate_hz", "g_local_m_s2", "pendulosity_kg_m", "inertia_kg_m2",
                   "damping_n_m_s", "stiffness_n_m_rad", "angle_sensor_v_rad", "preamp_gain", "adc_bits",
                   "adc_range_v", "pwm_full_scale_a", "pwm_counts", "torquer_n_m_a", "coil_tau_s", "delay_steps"},
                  ctx);
  p.loop_rate_hz = get_number(t, "loop_rate_hz", p.loop_rate_hz, 1000, 1e6);
  p.output_rate_hz = get_number(t, "output_rate_hz", p.output_rate_hz, 1, 1e5);
  p.g_local_m_s2 = get_number(t, "g_local_m_s2", p.g_local_m_s2, 9.7, 9.9);
  p.pendulosity_kg_m = get_number(t, "pendulosity_kg_m", p.pendulosity_kg_m, 1e-9, 1e-2);
  p.inertia_kg_m2 = get_number(t, "inertia_kg_m2", p.inertia_kg_m2, 1e-12, 1e-3);
  p.damping_n_m_s = get_number(t, "damping_n_m_s", p.damping_n_m_s, 0, 1);
  p.stiffness_n_m_rad = get_number(t, "stiffness_n_m_rad", p.stiffness_n_m_rad, 0, 10);
  p.angle_sensor_v_rad = get_number(t, "angle_sensor_v_rad", p.angle_sensor_v_rad, 1e-3, 1e6);
  p.preamp_gain = get_number(t, "preamp_gain", p.preamp_gain, 1e-3, 1e6);
  p.adc_bits = static_cast<int>(get_int(t, "adc_bits", p.adc_bits, 4, 32));
  p.adc_range_v = get_number(t, "adc_range_v", p.adc_range_v, 1e-3, 100);
  p.pwm_full_scale_a = get_number(t, "pwm_full_scale_a", p.pwm_full_scale_a, 1e-6, 10);
  p.pwm_counts = static_cast<int>(get_int(t, "pwm_counts", p.pwm_counts, 2, 1 << 24));
  p.torquer_n_m_a = get_number(t, "torquer_n_m_a", p.torquer_n_m_a, 1e-6, 10);
  p.coil_tau_s = get_number(t, "coil_tau_s", p.coil_tau_s, 1e-7, 1e-2);
  p.delay_steps = static_cast<int>(get_int(t, "delay_steps", p.delay_steps, 0, 1));
  const double ratio = p.loop_rate_hz / p.output_rate_hz;
  if (ratio < 1 || ratio != static_cast<double>(static_cast<int64_t>(ratio)))
    throw ConfigError(cfg::where(t) + ": loop_rate_hz must be an integer multiple of output_rate_hz");
}

void read_regulator_params(const toml::table& t, std::string_view ctx, RegulatorParams& p) {
  using cfg::get_number;
  cfg::check_keys(t, {"gain_a_per_v", "integral_corner_hz", "lead_zero_hz", "lead_pole_hz"}, ctx);
  p.gain_a_per_v = get_number(t, "gain_a_per_v", p.gain_a_per_v, 1e-9, 1e3);
  p.integral_corner_hz = get_number(t, "integral_corner_hz", p.integral_corner_hz, 0, 1e4);
  p.lead_zero_hz = get_number(t, "lead_zero_hz", p.lead_zero_hz, 0.01, 1e5);
  p.lead_pole_hz = get_number(t, "lead_pole_hz", p.lead_pole_hz, 0.01, 1e5);
}

}  // namespace rig::design
