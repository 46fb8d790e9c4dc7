#include "plant/dut/period_noise.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "rig/core/huge_pages.hpp"

namespace rig::plant {

namespace {
constexpr std::array<double, kBurstTones> kBurstHz = {265, 316, 470, 627, 697};  // docs/method.md, PSD bursts
}

NoiseBlock::NoiseBlock(std::size_t periods_in, std::size_t steps_in, double* storage)
    : periods(periods_in), steps(steps_in), bursting(periods) {
  const std::size_t n = periods * steps;
  auto take = [&storage](std::size_t count) {
    const std::span<double> s(storage, count);
    storage += count;
    return s;
  };
  slow_g = take(periods);
  temp_c = take(periods);
  vib = take(n);
  input = take(n);
  burst = take(n * kBurstTones);
  intf = take(n);
  poll_i = take(n);
  poll_q = take(n);
  sense = take(n);
}

PeriodNoise::PeriodNoise(const DutParams& p, uint64_t seed, std::size_t steps_per_period)
    : n_(p.noise), intrinsic_bias_g_(p.orientation.intrinsic_bias_g), loop_rate_hz_(p.loop.loop_rate_hz),
      output_rate_hz_(p.loop.output_rate_hz), dt_out_(1.0 / p.loop.output_rate_hz), steps_(steps_per_period) {
  const NoiseParams& n = n_;
  const double fs = loop_rate_hz_;
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
  flicker_ = noise::FlickerBank(on * n.flicker_b_g, n.flicker_tau_min_s, n.flicker_tau_max_s, dt_out_, r_flicker_);
  // The polling-frequency line's complex envelope (I, Q): each quadrature a flicker bank,
  // so the folded x reads B = polling_b_g and y reads |W_f(1 kHz)| times that.
  poll_i_ = noise::FlickerBank(on * n.polling_b_g, n.flicker_tau_min_s, n.flicker_tau_max_s, dt_out_, r_poll_i_);
  poll_q_ = noise::FlickerBank(on * n.polling_b_g, n.flicker_tau_min_s, n.flicker_tau_max_s, dt_out_, r_poll_q_);
  // ... and a slow drift of its amplitude from the power-on value (part of the intrinsic bias):
  // a random walk over the procedure's 110 min; in y it is cut by |W_f(1 kHz)| like the rest.
  poll_drift_i_ = noise::GaussMarkov(on * n.polling_k_g_per_rts, n.polling_drift_tau_s, dt_out_);
  poll_drift_q_ = noise::GaussMarkov(on * n.polling_k_g_per_rts, n.polling_drift_tau_s, dt_out_);
  poll_osc_.set(p.loop.output_rate_hz + n.polling_offset_hz, fs, 0.0);
  rrw_step_ = on * n.rrw_k_g_per_rts * std::sqrt(dt_out_);
  vib_ = noise::BandNoise(n.vibration_f_lo_hz, n.vibration_f_hi_hz, fs, on * n.vibration_rms_g);
  intf_ = noise::LineBand(n.interference_f_lo_hz, n.interference_f_hi_hz, n.interference_lines,
                          n.interference_coherence_s, on * n.interference_rms_g, fs, dt_out_, r_intf_);
  burst_p_ = on * n.burst_rate_per_h / 3600.0 * dt_out_;
  burst_decay_ = std::exp(-dt_out_ / n.burst_decay_s);
  for (std::size_t j = 0; j < burst_osc_.size(); ++j) burst_osc_[j].set(kBurstHz[j], fs, 0.0);
}

double PeriodNoise::slow_bias_g(double& temp_c) {
  const NoiseParams& n = n_;
  const double t = static_cast<double>(n_out_) / output_rate_hz_;  // the DUT's time_s()
  rrw_ += rrw_step_ * r_rrw_.normal();
  temp_c = n.ambient_c + n.warmup_rise_c * (1 - std::exp(-t / n.warmup_tau_s));
  const double on = n.enabled ? 1.0 : 0.0;
  return intrinsic_bias_g_ + flicker_.step(r_flicker_) + rrw_ +
         on * (n.ramp_r_g_per_s * t + n.bias_tempco_g_per_c * (temp_c - n.ambient_c));
}

void PeriodNoise::fill(NoiseBlock& b) {
  for (std::size_t i = 0; i < b.periods; ++i) period(b, i);
  // The three per-step streams that never depend on the period (vibration, input and sense
  // white noise) over the whole block at once, each in its own loop: every stream is its own
  // generator, so each draws what it drew inside the period loop, in the same order, and the
  // terms keep every bit. Apart, each loop holds its state in registers; together with the
  // period's oscillators they spilled, and a loop of ten steps per period paid its set-up ten
  // times a millisecond (2026-11-28: the worker was the `paper` procedure's critical path).
  const std::size_t steps = b.periods * b.steps;
  noise::BandNoise vib = vib_;
  noise::Rng r = r_vib_;
  for (std::size_t k = 0; k < steps; ++k) b.vib[k] = vib.step(r);
  vib_ = vib;
  r_vib_ = r;
  if (input_sd_ > 0) draw_white(r_input_, input_sd_, b.input.data(), steps);
  if (sense_sd_ > 0) draw_white(r_sense_, sense_sd_, b.sense.data(), steps);
}

void PeriodNoise::draw_white(noise::Rng& rng, double sd, double* out, std::size_t n) {
  noise::Rng r = rng;
  for (std::size_t k = 0; k < n; ++k) out[k] = sd * r.normal();
  rng = r;
}

void PeriodNoise::period(NoiseBlock& b, std::size_t i) {
  b.slow_g[i] = slow_bias_g(b.temp_c[i]);
  ++n_out_;
  // bursts: Poisson arrivals, exponentially decaying tones (input acceleration)
  for (std::size_t j = 0; j < burst_env_.size(); ++j) {
    burst_env_[j] *= burst_decay_;
    if (burst_p_ > 0 && r_burst_.uniform() < burst_p_) {
      burst_env_[j] += n_.burst_peak_g;
      burst_osc_[j].set(kBurstHz[j], loop_rate_hz_, 2 * std::numbers::pi * r_burst_.uniform());
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
  b.bursting[i] = bursting;

  const std::size_t n = steps_, at = i * n;
  // The interference lines of the whole period at once (LineBand::fill: step()'s bits).
  intf_.fill(std::span<double>(b.intf.data() + at, n));
  // One pass over the period's oscillators in locals (so the compiler keeps their states in
  // registers rather than in this object, which the stores might alias): the polling line's
  // carrier and, while a burst rings, the five tones. The white streams are fill()'s.
  noise::Oscillator poll = poll_osc_;
  std::array<noise::Oscillator, kBurstTones> tone = burst_osc_;
  const std::array<double, kBurstTones> env = burst_env_;
  double* burst_out = b.burst.data() + at * kBurstTones;
  double* pi_out = b.poll_i.data() + at;
  double* pq_out = b.poll_q.data() + at;
  for (std::size_t k = 0; k < n; ++k) {
    if (bursting)
      for (std::size_t j = 0; j < kBurstTones; ++j) {
        burst_out[k * kBurstTones + j] = env[j] * tone[j].c;
        tone[j].step();
      }
    pi_out[k] = pi_amp * poll.c;
    pq_out[k] = pq_amp * poll.s;
    poll.step();
  }
  poll_osc_ = poll;
  burst_osc_ = tone;
}

NoisePipe::NoisePipe(PeriodNoise source, std::size_t periods_per_block, std::size_t depth)
    : source_(std::move(source)) {
  depth = std::max<std::size_t>(depth, 1);
  const std::size_t steps = source_.steps_per_period(), each = NoiseBlock::doubles(periods_per_block, steps);
  // Uninitialised: the worker writes every term before the reader reads it. Huge pages: the
  // ring is written once per DUT (rig filter select makes one per candidate), about 14 MB, which
  // on 4 KiB pages was 3 600 page faults.
  arena_ = std::make_unique_for_overwrite<double[]>(depth * each);
  advise_huge_pages(arena_.get(), depth * each * sizeof(double));
  ring_.reserve(depth);
  for (std::size_t i = 0; i < depth; ++i) ring_.emplace_back(periods_per_block, steps, arena_.get() + i * each);
  low_ = depth / 2;
  ready_ = std::max<std::size_t>(low_, 1);
  worker_ = std::thread([this] { run(); });  // after everything it reads is built
}

NoisePipe::~NoisePipe() {
  {
    const std::lock_guard lock(m_);
    stop_ = true;
  }
  worker_cv_.notify_one();
  worker_.join();
}

void NoisePipe::run() {
  // Only arithmetic on memory allocated before the thread started: nothing here can throw.
  // When the ring is full the worker sleeps until half of it is free again, so the reader
  // wakes it once per ring_.size() / 2 blocks, not at every block.
  std::unique_lock lock(m_);
  for (;;) {
    if (drawn_ - released_ == ring_.size()) {
      worker_waiting_ = true;
      worker_cv_.wait(lock, [this] { return stop_ || drawn_ - released_ <= low_; });
      worker_waiting_ = false;
    }
    if (stop_) return;
    NoiseBlock& b = ring_[drawn_ % ring_.size()];
    lock.unlock();  // the block is the worker's until drawn_ counts it
    source_.fill(b);
    lock.lock();
    ++drawn_;
    // A waiting reader is woken once half the ring is drawn, not at every block: the two threads
    // run at about the same speed, and a hand-over per block cost a futex wake and a sleep each
    // way (30 000 context switches per `paper` run, a second of system time on a VM).
    if (reader_waiting_ && drawn_ - released_ >= ready_) reader_cv_.notify_one();
  }
}

const NoiseBlock& NoisePipe::front() {
  std::unique_lock lock(m_);
  if (drawn_ == released_) {
    reader_waiting_ = true;
    reader_cv_.wait(lock, [this] { return drawn_ - released_ >= ready_; });
    reader_waiting_ = false;
  }
  return ring_[released_ % ring_.size()];
}

void NoisePipe::pop() {
  bool wake = false;
  {
    const std::lock_guard lock(m_);
    ++released_;
    wake = worker_waiting_ && drawn_ - released_ <= low_;
  }
  if (wake) worker_cv_.notify_one();
}

}  // namespace rig::plant
