// The emulated DUT (issue 4): closed loop of docs/method.md Fig. 3 with its noise
// sources, behind the DutSource seam.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "plant/dut/emulated_dut.hpp"

namespace rig::plant {

EmulatedDut::EmulatedDut(const DutParams& p, uint64_t seed_in) : p_(p), loop_(p.loop, p.regulator) {
  const uint64_t seed = p.seed.value_or(seed_in);
  const double fs = p_.loop.loop_rate_hz;
  steps_per_out_ = static_cast<int>(std::lround(fs / p_.loop.output_rate_hz));
  const NoiseParams& n = p_.noise;
  const std::size_t steps = static_cast<std::size_t>(std::max(steps_per_out_, 0));
  PeriodNoise source(p_, seed, steps);
  has_input_ = source.has_input();
  has_sense_ = source.has_sense();
  sense_lsb_ = 2 * n.range_g / std::ldexp(1.0, n.sense_adc_bits);
  sense_inv_lsb_ = 1 / sense_lsb_;
  // Blocks of 1024 periods at the default rates (1.024 s), sixteen ahead (about 14 MB of
  // terms): the two threads run at about the same speed, and with blocks of 128, eight ahead,
  // they kept meeting an empty or a full ring: 30 000 context switches per `paper` run, and
  // 5.9 s against 3.4 s wall on a 2-core VM (2026-11-28, bench/analysis/bench_paper.sh; the
  // same passport).
  noise_ = std::make_unique<NoisePipe>(std::move(source), noise_block_periods(steps), kNoiseBlocksAhead);
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
  if (block_ == nullptr || period_ == block_->periods) {
    if (block_ != nullptr) noise_->pop();
    block_ = &noise_->front();
    period_ = 0;
  }
  const NoiseBlock& b = *block_;
  const std::size_t i = period_++;
  temp_c_ = b.temp_c[i];
  // The loop test's torque acts on the pendulum like an input acceleration (torque = ml g q).
  const double q_slow = q_static_ + b.slow_g[i] + q_test_g;
  const bool bursting = b.bursting[i] != 0;

  // Hot loop: locals so the compiler keeps the states in registers. The noise terms add in the
  // order they always did (the same bits): q = q_slow + vibration + input + each burst tone;
  // x = loop + lines + pick-up I - pick-up Q + sense.
  const std::size_t n = b.steps, at = i * n;
  const double* vib = b.vib.data() + at;
  const double* input = b.input.data() + at;
  const double* burst = b.burst.data() + at * kBurstTones;
  const double* intf = b.intf.data() + at;
  const double* poll_i = b.poll_i.data() + at;
  const double* poll_q = b.poll_q.data() + at;
  const double* sense = b.sense.data() + at;
  design::LoopModel::State st = st_;
  const bool filter_on = filter_cfg_.enabled;
  bool tap_saturated = tap_saturated_;
  double x = 0, y = 0;
  // The steps of the period, with `filter` the output filter W_f(z) of one value.
  auto steps = [&](auto&& filter) {
    for (std::size_t k = 0; k < n; ++k) {
      double q = q_slow + vib[k];
      if (has_input_) q += input[k];
      if (bursting)
        for (std::size_t j = 0; j < kBurstTones; ++j) q += burst[k * kBurstTones + j];
      // x: the torquer current through the current-sense channel, with its pick-up
      double xm = loop_.step(st, q) + intf[k] + poll_i[k] - poll_q[k];
      if (has_sense_) xm += sense[k];
      x = sense_lsb_ * design::round_half_even(xm * sense_inv_lsb_);
      y = filter_on ? filter(x) : x;
      if (x_tap) {  // the loop test's record, at the loop rate
        x_tap[k] = static_cast<float>(x);
        y_tap[k] = static_cast<float>(y);
        tap_saturated = tap_saturated || st.saturated;
      }
    }
  };
  if (filt_.size() == 1) {  // the usual single biquad: its state in registers, not in the vector
    design::Section sec = filt_[0];
    steps([&sec](double v) { return sec.step(v); });
    filt_[0] = sec;
  } else {
    steps([this](double v) {
      for (auto& sec : filt_) v = sec.step(v);
      return v;
    });
  }
  tap_saturated_ = tap_saturated;
  st_ = st;
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
