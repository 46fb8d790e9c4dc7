// The emulated DUT (issue 4): closed loop of docs/method.md Fig. 3 with its noise
// sources, behind the DutSource seam.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "plant/dut/emulated_dut.hpp"

namespace rig::plant {

namespace {
constexpr std::array<double, 5> kBurstHz = {265, 316, 470, 627, 697};  // docs/method.md, PSD bursts
}

EmulatedDut::EmulatedDut(const DutParams& p, uint64_t seed_in) : p_(p), loop_(p.loop, p.regulator) {
  const uint64_t seed = p.seed.value_or(seed_in);
  const double fs = p_.loop.loop_rate_hz;
  steps_per_out_ = static_cast<int>(std::lround(fs / p_.loop.output_rate_hz));
  scratch_.assign(static_cast<std::size_t>(std::max(steps_per_out_, 0)), 0.0);
  dt_out_ = 1.0 / p_.loop.output_rate_hz;
  const NoiseParams& n = p_.noise;
  r_sense_ = noise::Rng(seed, kSense);
  r_input_ = noise::Rng(seed, kInput);
  r_flicker_ = noise::Rng(seed, kFlicker);
  r_rrw_ = noise::Rng(seed, kRrw);
  r_vib_ = noise::Rng(seed, kVib);
  r_burst_ = noise::Rng(seed, kBurst);
  r_intf_ = noise::Rng(seed, kIntf);
  r_poll_i_ = noise::Rng(seed, kPollI);
  r_poll_q_ = noise::Rng(seed, kPollQ);
  r_poll_drift_ = noise::Rng(seed, kPollDrift);
  const double on = n.enabled ? 1.0 : 0.0;
  // White densities (one-sided, g/sqrt(Hz)) to per-sample sd at the loop rate: sd = d sqrt(fs/2).
  sense_sd_ = on * n.sense_white_g_rthz * std::sqrt(fs / 2);
  input_sd_ = on * n.input_white_g_rthz * std::sqrt(fs / 2);
  sense_lsb_ = 2 * n.range_g / std::ldexp(1.0, n.sense_adc_bits);
  sense_inv_lsb_ = 1 / sense_lsb_;
  flicker_ = noise::FlickerBank(on * n.flicker_b_g, n.flicker_tau_min_s, n.flicker_tau_max_s, dt_out_, r_flicker_);
  // The polling-frequency line's complex envelope (I, Q): each quadrature a flicker bank,
  // so the folded x reads B = polling_b_g and y reads |W_f(1 kHz)| times that.
  poll_i_ = noise::FlickerBank(on * n.polling_b_g, n.flicker_tau_min_s, n.flicker_tau_max_s, dt_out_, r_poll_i_);
  poll_q_ = noise::FlickerBank(on * n.polling_b_g, n.flicker_tau_min_s, n.flicker_tau_max_s, dt_out_, r_poll_q_);
  // ... and a slow drift of its amplitude from the power-on value (part of the intrinsic bias):
  // a random walk over the procedure's 110 min; in y it is cut by |W_f(1 kHz)| like the rest.
  poll_drift_i_ = noise::GaussMarkov(on * n.polling_k_g_per_rts, n.polling_drift_tau_s, dt_out_);
  poll_drift_q_ = noise::GaussMarkov(on * n.polling_k_g_per_rts, n.polling_drift_tau_s, dt_out_);
  poll_osc_.set(p_.loop.output_rate_hz + n.polling_offset_hz, fs, 0.0);
  rrw_step_ = on * n.rrw_k_g_per_rts * std::sqrt(dt_out_);
  vib_ = noise::BandNoise(n.vibration_f_lo_hz, n.vibration_f_hi_hz, fs, on * n.vibration_rms_g);
  intf_ = noise::LineBand(n.interference_f_lo_hz, n.interference_f_hi_hz, n.interference_lines,
                          n.interference_coherence_s, on * n.interference_rms_g, fs, dt_out_, r_intf_);
  burst_p_ = on * n.burst_rate_per_h / 3600.0 * dt_out_;
  burst_decay_ = std::exp(-dt_out_ / n.burst_decay_s);
  for (std::size_t j = 0; j < burst_osc_.size(); ++j) burst_osc_[j].set(kBurstHz[j], fs, 0.0);
  set_filter(p_.filter);
  set_table_angle_deg(p_.orientation.u10_angle_deg);
  temp_c_ = n.ambient_c;
  // The loop locks within milliseconds of power-on; start from that locked state so
  // the first samples the rig sees are not a start-up transient.
  const double q0 = q_static_ + p_.orientation.intrinsic_bias_g;
  for (int k = 0; k < static_cast<int>(0.2 * fs); ++k) loop_.step(st_, q0);
}

void EmulatedDut::set_table_angle_deg(double deg) {
  // Table axis = the nominal sensitive axis, tilted by e above the horizon. The
  // sensitive axis leaves the table axis by (misalignment in the pendulum plane,
  // cross-misalignment in the hinge plane); turning the table by theta turns that
  // offset about the axis, so its vertical projection is
  //   sin(e) + cos(e) (sin(d) cos(theta) + sin(d_x) sin(theta)).
  if (deg == angle_deg_) return;  // the world sets the angle every step; trig only on change
  angle_deg_ = deg;
  const OrientationParams& o = p_.orientation;
  const double th = (deg - o.u10_angle_deg) * std::numbers::pi / 180.0;
  q_static_ = std::sin(o.table_tilt_rad) +
              std::cos(o.table_tilt_rad) *
                  (std::sin(o.misalignment_rad) * std::cos(th) + std::sin(o.cross_misalignment_rad) * std::sin(th));
}

void EmulatedDut::set_filter(const FilterConfig& f) {
  const bool same_shape = f.sections.size() == filter_cfg_.sections.size();
  filter_cfg_ = f;
  filter_cfg_.rate_hz = p_.loop.loop_rate_hz;
  std::vector<design::Section> s;
  for (std::size_t i = 0; i < f.sections.size(); ++i) {
    design::Section sec{f.sections[i]};
    if (same_shape) {  // keep the state: the MCU swaps coefficients in place
      sec.w1 = filt_[i].w1;
      sec.w2 = filt_[i].w2;
    }
    s.push_back(sec);
  }
  filt_ = std::move(s);
}

double EmulatedDut::slow_bias_g() {
  const NoiseParams& n = p_.noise;
  const double t = time_s();
  rrw_ += rrw_step_ * r_rrw_.normal();
  temp_c_ = n.ambient_c + n.warmup_rise_c * (1 - std::exp(-t / n.warmup_tau_s));
  const double on = n.enabled ? 1.0 : 0.0;
  return p_.orientation.intrinsic_bias_g + flicker_.step(r_flicker_) + rrw_ +
         on * (n.ramp_r_g_per_s * t + n.bias_tempco_g_per_c * (temp_c_ - n.ambient_c));
}

double EmulatedDut::word(double v, double& carry) const {
  // Fixed-point output word; the rounding remainder goes into the next word, so the
  // sum of words (the velocity) stays exact: the quantisation term Q of IEEE 1293.
  const double lsb = p_.noise.output_lsb_g;
  if (lsb <= 0) return v;
  const double want = v + carry;
  const double out = lsb * design::round_half_even(want / lsb);
  carry = want - out;
  return out;
}

void EmulatedDut::next(float& x_g, float& y_g) {
  double x, y;
  next(x, y);
  x_g = static_cast<float>(x);
  y_g = static_cast<float>(y);
}

void EmulatedDut::next(double& x_out, double& y_out) { period(0.0, nullptr, nullptr, x_out, y_out); }

bool EmulatedDut::next_under_test(double torque_g, std::span<float> x_loop, std::span<float> y_loop) {
  if (x_loop.size() < static_cast<std::size_t>(steps_per_out_) || y_loop.size() < x_loop.size())
    throw std::invalid_argument("next_under_test: the taps need loop_steps_per_output() values each");
  double x, y;
  tap_saturated_ = false;
  period(torque_g, x_loop.data(), y_loop.data(), x, y);
  return tap_saturated_;
}

void EmulatedDut::period(double q_test_g, float* x_tap, float* y_tap, double& x_out, double& y_out) {
  // The loop test's torque acts on the pendulum like an input acceleration (torque = ml g q).
  const double q_slow = q_static_ + slow_bias_g() + q_test_g;
  // bursts: Poisson arrivals, exponentially decaying tones (input acceleration)
  for (std::size_t j = 0; j < burst_env_.size(); ++j) {
    burst_env_[j] *= burst_decay_;
    if (burst_p_ > 0 && r_burst_.uniform() < burst_p_) {
      burst_env_[j] += p_.noise.burst_peak_g;
      burst_osc_[j].set(kBurstHz[j], p_.loop.loop_rate_hz, 2 * std::numbers::pi * r_burst_.uniform());
    }
    if (burst_env_[j] < 1e-15) burst_env_[j] = 0;
    burst_osc_[j].renormalise();
  }
  const double pi_amp = poll_i_.step(r_poll_i_) + poll_drift_i_.step(r_poll_drift_);
  const double pq_amp = poll_q_.step(r_poll_q_) + poll_drift_q_.step(r_poll_drift_);
  intf_.update_envelopes(r_intf_);
  poll_osc_.renormalise();

  bool bursting = false;
  for (double e : burst_env_) bursting = bursting || e != 0;

  // The interference pick-up of the whole period first: its lines do not depend on the loop,
  // and line by line (pairs of lines side by side) their carriers stay in registers. Per step
  // the lines add in the same order as LineBand::step's, so x gets the same bits.
  const std::size_t n = static_cast<std::size_t>(std::max(steps_per_out_, 0));
  const std::span<double> intf(scratch_.data(), n);
  intf_.fill(intf);

  // Hot loop: locals so the compiler keeps the states in registers.
  design::LoopModel::State st = st_;
  noise::Oscillator poll = poll_osc_;
  const bool filter_on = filter_cfg_.enabled;
  double x = 0, y = 0;
  for (std::size_t k = 0; k < n; ++k) {
    double q = q_slow + vib_.step(r_vib_);
    if (input_sd_ > 0) q += input_sd_ * r_input_.normal();
    if (bursting) {
      for (std::size_t j = 0; j < burst_env_.size(); ++j) {
        q += burst_env_[j] * burst_osc_[j].c;
        burst_osc_[j].step();
      }
    }
    // x: the torquer current through the current-sense channel, with its pick-up
    double xm = loop_.step(st, q) + intf[k] + pi_amp * poll.c - pq_amp * poll.s;
    poll.step();
    if (sense_sd_ > 0) xm += sense_sd_ * r_sense_.normal();
    x = sense_lsb_ * design::round_half_even(xm * sense_inv_lsb_);
    y = x;
    if (filter_on)
      for (auto& sec : filt_) y = sec.step(y);
    if (x_tap) {  // the loop test's record, at the loop rate
      x_tap[k] = static_cast<float>(x);
      y_tap[k] = static_cast<float>(y);
      tap_saturated_ = tap_saturated_ || st.saturated;
    }
  }
  st_ = st;
  poll_osc_ = poll;
  ++n_out_;
  // The rig polls: sample-and-hold of the last x, y, no anti-alias filter.
  x_out = word(x, carry_x_);
  y_out = word(y, carry_y_);
}

std::unique_ptr<DutSource> make_dut_source(const toml::table* dut_cfg, uint64_t seed, const std::string& serial) {
  DutParams p = load_dut_params(dut_cfg);
  if (!serial.empty()) p.serial = serial;
  return std::make_unique<EmulatedDut>(p, seed);
}

}  // namespace rig::plant
