// Physical parameters of the emulated quartz pendulum accelerometer (docs/method.md
// Fig. 3): its loop and regulator as designed (design/loop_params.hpp), its noise
// sources and its geometry on the table. Loaded from the default DUT profile
// (plant/dut/default.toml, compiled in) with a profile's [plant.dut] overrides.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "rig/core/filter_config.hpp"
#include "design/loop_params.hpp"

namespace rig::plant {

// Geometry of the DUT on the table (rotation about the nominal sensitive axis).
struct OrientationParams {
  double intrinsic_bias_g = -5.0e-4;      // zero-signal offset of the instrument itself
  double misalignment_rad = 3.8549e-4;    // sensitive axis out of the table plane, in the
                                          // pendulum plane: gives the base error that flips sign
  double cross_misalignment_rad = 2e-4;   // the same, in the hinge plane: shows table angle errors
  double table_tilt_rad = 0;              // table axis above the horizon: adds g*tilt to the bias
  double u10_angle_deg = 0;               // table angle at which the pendulum points down
};

// Noise and disturbances. Amplitudes are of the physical process; how they
// show in the rig's Allan analysis is the calibration in docs/plant.md.
struct NoiseParams {
  bool enabled = true;
  // current-sense channel of x (electronics after the loop, before W_f)
  double sense_white_g_rthz = 0;   // wide-band noise density, g/sqrt(Hz), up to loop_rate/2
  int sense_adc_bits = 18;         // current-sense ADC resolution over the +-range
  double range_g = 12;             // full scale of the current-sense / output word, g
  // output word: the DUT sends x, y as fixed-point words; the rounding remainder is carried
  // into the next word (velocity-preserving), which is the IEEE 1293 quantisation term Q
  double output_lsb_g = 0;
  // input-referred acceleration noise (pendulum Brownian + pick-off), white
  double input_white_g_rthz = 0;
  // bias instability: flicker of the bias from a bank of Gauss-Markov processes, B in g
  double flicker_b_g = 0;
  double flicker_tau_min_s = 0.5, flicker_tau_max_s = 20000;
  double rrw_k_g_per_rts = 0;     // rate random walk K, g/sqrt(s)
  double ramp_r_g_per_s = 0;      // rate ramp R (ageing), g/s
  // temperature: warm-up after power-on, bias sensitivity
  double ambient_c = 22, warmup_rise_c = 3, warmup_tau_s = 900, bias_tempco_g_per_c = 0;
  // building vibration, 70-76 Hz: band-limited acceleration (band-pass filtered white noise)
  double vibration_rms_g = 0;
  double vibration_f_lo_hz = 70, vibration_f_hi_hz = 76;
  // bursts (trams, people, switching): decaying tones at the listed frequencies
  double burst_peak_g = 0;
  double burst_rate_per_h = 20;   // mean arrivals per hour, per frequency
  double burst_decay_s = 2;
  // interference near the polling frequency, 795-970 Hz: pick-up in the current sense
  double interference_rms_g = 0;
  double interference_f_lo_hz = 795, interference_f_hi_hz = 970;
  int interference_lines = 6;
  double interference_coherence_s = 2;
  // interference at the 1 kHz polling frequency itself (bus activity pick-up); its
  // amplitude flickers: sampled at 1 kHz it folds to near-DC, filtered by |W_f(1 kHz)|
  double polling_b_g = 0;         // the B an Allan analysis of the folded process reads
  double polling_offset_hz = 0;   // frequency offset between DUT and rig clocks
  // slow drift of the same pick-up's amplitude (the interfering harmonic follows the
  // temperature / load of the equipment that radiates it): per quadrature a Gauss-Markov
  // process started at 0 at power-on, correlation time polling_drift_tau_s; over t << tau
  // it is a random walk with the rate-random-walk coefficient polling_k_g_per_rts
  double polling_k_g_per_rts = 0;
  double polling_drift_tau_s = 36000;
};

struct DutParams {
  std::string serial = "EMU-QPA-0001";
  std::optional<uint64_t> seed;  // [plant.dut].seed overrides the seed given by the rig
  design::LoopParams loop;
  design::RegulatorParams regulator;
  OrientationParams orientation;
  NoiseParams noise;
  FilterConfig filter;  // the output filter at power-on (the paper's W_f(z))
};

// The default DUT profile (plant/dut/default.toml) as compiled into the binary.
std::string_view default_dut_toml();

// Defaults merged with `overrides` (the profile's [plant.dut] table, may be null).
// Unknown keys and bad values throw ConfigError with file:line:col and the table as `section`
// names it: "plant.dut" in a profile; "" for a DUT file read whole, whose [loop] is [loop].
DutParams load_dut_params(const toml::table* overrides, std::string_view section = "plant.dut");

}  // namespace rig::plant
