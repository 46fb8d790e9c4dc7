#include "plant/dut/params.hpp"

#include <string>

#include "design/filter.hpp"
#include "design/filter_toml.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::plant {
namespace {

using cfg::get_bool;
using cfg::get_int;
using cfg::get_number;

// Reads `key` into `v` when present (the merged table always holds the defaults).
void num(const toml::table& t, std::string_view key, double& v, std::optional<double> lo = std::nullopt,
         std::optional<double> hi = std::nullopt) {
  v = get_number(t, key, v, lo, hi);
}
void integer(const toml::table& t, std::string_view key, int& v, int64_t lo, int64_t hi) {
  v = static_cast<int>(get_int(t, key, v, lo, hi));
}

void read_orientation(const toml::table& t, OrientationParams& p, const std::string& ctx) {
  cfg::check_keys(t,
                  {"intrinsic_bias_g", "misalignment_rad", "cross_misalignment_rad", "table_tilt_rad",
                   "u10_angle_deg"},
                  ctx);
  num(t, "intrinsic_bias_g", p.intrinsic_bias_g, -1, 1);
  num(t, "misalignment_rad", p.misalignment_rad, -0.1, 0.1);
  num(t, "cross_misalignment_rad", p.cross_misalignment_rad, -0.1, 0.1);
  num(t, "table_tilt_rad", p.table_tilt_rad, -0.1, 0.1);
  num(t, "u10_angle_deg", p.u10_angle_deg, -360, 360);
}

void read_noise(const toml::table& t, NoiseParams& p, const std::string& ctx) {
  cfg::check_keys(
      t,
      {"enabled", "sense_white_g_rthz", "sense_adc_bits", "range_g", "output_lsb_g", "input_white_g_rthz",
       "flicker_b_g", "flicker_tau_min_s", "flicker_tau_max_s", "rrw_k_g_per_rts", "ramp_r_g_per_s", "ambient_c",
       "warmup_rise_c", "warmup_tau_s", "bias_tempco_g_per_c", "vibration_rms_g", "vibration_f_lo_hz",
       "vibration_f_hi_hz", "burst_peak_g", "burst_rate_per_h",
       "burst_decay_s", "interference_rms_g", "interference_f_lo_hz", "interference_f_hi_hz", "interference_lines",
       "interference_coherence_s", "polling_b_g", "polling_offset_hz", "polling_k_g_per_rts",
       "polling_drift_tau_s"},
      ctx);
  p.enabled = get_bool(t, "enabled", p.enabled);
  num(t, "sense_white_g_rthz", p.sense_white_g_rthz, 0, 1);
  integer(t, "sense_adc_bits", p.sense_adc_bits, 4, 40);
  num(t, "range_g", p.range_g, 0.1, 1000);
  num(t, "output_lsb_g", p.output_lsb_g, 0, 1);
  num(t, "input_white_g_rthz", p.input_white_g_rthz, 0, 1);
  num(t, "flicker_b_g", p.flicker_b_g, 0, 1);
  num(t, "flicker_tau_min_s", p.flicker_tau_min_s, 1e-3, 1e7);
  num(t, "flicker_tau_max_s", p.flicker_tau_max_s, 1e-3, 1e8);
  if (p.flicker_tau_max_s <= p.flicker_tau_min_s)
    throw ConfigError(cfg::where(t) + ": flicker_tau_max_s must exceed flicker_tau_min_s");
  num(t, "rrw_k_g_per_rts", p.rrw_k_g_per_rts, 0, 1);
  num(t, "ramp_r_g_per_s", p.ramp_r_g_per_s, -1, 1);
  num(t, "ambient_c", p.ambient_c, -60, 120);
  num(t, "warmup_rise_c", p.warmup_rise_c, -50, 50);
  num(t, "warmup_tau_s", p.warmup_tau_s, 1e-3, 1e7);
  num(t, "bias_tempco_g_per_c", p.bias_tempco_g_per_c, -1, 1);
  num(t, "vibration_rms_g", p.vibration_rms_g, 0, 10);
  num(t, "vibration_f_lo_hz", p.vibration_f_lo_hz, 0.1, 5000);
  num(t, "vibration_f_hi_hz", p.vibration_f_hi_hz, 0.1, 5000);
  num(t, "burst_peak_g", p.burst_peak_g, 0, 10);
  num(t, "burst_rate_per_h", p.burst_rate_per_h, 0, 1e6);
  num(t, "burst_decay_s", p.burst_decay_s, 1e-3, 1e4);
  num(t, "interference_rms_g", p.interference_rms_g, 0, 10);
  num(t, "interference_f_lo_hz", p.interference_f_lo_hz, 0.1, 5000);
  num(t, "interference_f_hi_hz", p.interference_f_hi_hz, 0.1, 5000);
  integer(t, "interference_lines", p.interference_lines, 1, 64);
  num(t, "interference_coherence_s", p.interference_coherence_s, 1e-3, 1e6);
  num(t, "polling_b_g", p.polling_b_g, 0, 1);
  num(t, "polling_offset_hz", p.polling_offset_hz, -10, 10);
  num(t, "polling_k_g_per_rts", p.polling_k_g_per_rts, 0, 1);
  num(t, "polling_drift_tau_s", p.polling_drift_tau_s, 1, 1e9);
}

// Applies one layer (the compiled-in default, then the profile's overrides) onto `p`.
// Layers are read one by one, not merged, so errors keep the file:line of their layer.
void apply_layer(const toml::table& root, DutParams& p, std::string_view section) {
  // What errors call a sub-table: "plant.dut.loop" in a profile, "loop" in a DUT file.
  const auto in = [section](std::string_view name) {
    return section.empty() ? std::string(name) : std::string(section) + "." + std::string(name);
  };
  cfg::check_keys(root, {"serial", "seed", "loop", "regulator", "orientation", "noise", "filter"},
                  section.empty() ? "DUT file" : section);
  p.serial = cfg::get_string(root, "serial", p.serial);
  if (root.contains("seed")) p.seed = static_cast<uint64_t>(get_int(root, "seed", std::nullopt, 0));
  if (const toml::table* t = cfg::get_table(root, "loop")) design::read_loop_params(*t, in("loop"), p.loop);
  if (const toml::table* t = cfg::get_table(root, "regulator"))
    design::read_regulator_params(*t, in("regulator"), p.regulator);
  if (const toml::table* t = cfg::get_table(root, "orientation")) read_orientation(*t, p.orientation, in("orientation"));
  if (const toml::table* t = cfg::get_table(root, "noise")) read_noise(*t, p.noise, in("noise"));
  if (const toml::table* t = cfg::get_table(root, "filter"))
    design::read_filter_table(*t, in("filter"), design::RateKey::absent, p.filter);
}

}  // namespace

DutParams load_dut_params(const toml::table* overrides, std::string_view section) {
  DutParams p;
  p.filter = design::paper_wf();
  apply_layer(cfg::parse_string(default_dut_toml(), "plant/dut/default.toml"), p, "plant.dut");
  if (overrides) apply_layer(*overrides, p, section);
  p.filter.rate_hz = p.loop.loop_rate_hz;
  return p;
}

}  // namespace rig::plant
