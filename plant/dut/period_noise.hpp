// The emulated DUT's noise, computed ahead of its loop (issue 17). Everything the model adds to
// the loop's input and to x in an output period -- the slow bias, bursts, vibration, input
// and sense white noise, the interference lines, the polling pick-up -- comes from its own
// random stream and oscillators and never depends on the loop's state, the table angle, the
// filter or a loop test. So PeriodNoise draws it period by period into NoiseBlocks, and
// NoisePipe does that on a worker thread a few blocks ahead while the rig's thread steps the
// loop: every stream is drawn in the same order as when the loop drew it, and each term is
// stored as the value the loop used to add, so the model's output keeps every bit.
#pragma once
#include <array>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "plant/dut/noise.hpp"
#include "plant/dut/params.hpp"

namespace rig::plant {

inline constexpr int kBurstTones = 5;

// The noise of `periods` consecutive output periods of `steps` loop steps each. Per period:
// the slow bias (g) and the temperature it implies, and whether a burst rings. Per loop step
// (period-major): the terms in the order the loop adds them. The terms live in storage the
// block is given (in the pipe's ring, one arena for all blocks) and are uninitialised until
// drawn; `burst` is written only while a burst rings.
struct NoiseBlock {
  NoiseBlock(std::size_t periods, std::size_t steps, double* storage);  // doubles() of them
  NoiseBlock(const NoiseBlock&) = delete;  // a copy would share the terms
  NoiseBlock& operator=(const NoiseBlock&) = delete;
  NoiseBlock(NoiseBlock&&) = default;
  static std::size_t doubles(std::size_t periods, std::size_t steps) {
    return periods * (2 + steps * (7 + kBurstTones));
  }
  std::size_t periods, steps;
  std::vector<char> bursting;
  std::span<double> slow_g, temp_c;
  std::span<double> vib, input;                   // input acceleration (g): vibration, white
  std::span<double> burst;                        // kBurstTones terms per step
  std::span<double> intf, poll_i, poll_q, sense;  // added to x (g): lines, pick-up I and Q, white
};

// The DUT's noise sources, one random stream each (the streams and their seeds as the model
// has always drawn them), advanced one output period at a time.
class PeriodNoise {
 public:
  PeriodNoise(const DutParams& p, uint64_t seed, std::size_t steps_per_period);
  // The next b.periods periods into b.
  void fill(NoiseBlock& b);
  std::size_t steps_per_period() const { return steps_; }
  // Whether the input and the sense channel carry white noise (the terms are then added).
  bool has_input() const { return input_sd_ > 0; }
  bool has_sense() const { return sense_sd_ > 0; }

 private:
  void period(NoiseBlock& b, std::size_t i);  // the per-period terms and the oscillators
  static void draw_white(noise::Rng& rng, double sd, double* out, std::size_t n);
  double slow_bias_g(double& temp_c);  // bias terms updated once per output period

  enum Stream : uint64_t {
    kSense = 1, kInput, kFlicker, kRrw, kVib, kBurst, kIntf, kPollI, kPollQ, kPickoff, kPollDrift
  };
  NoiseParams n_;
  double intrinsic_bias_g_, loop_rate_hz_, output_rate_hz_, dt_out_;
  std::size_t steps_;
  uint64_t n_out_ = 0;  // periods drawn
  noise::Rng r_sense_, r_input_, r_flicker_, r_rrw_, r_vib_, r_burst_, r_intf_, r_poll_i_, r_poll_q_,
      r_poll_drift_;
  noise::FlickerBank flicker_, poll_i_, poll_q_;
  noise::GaussMarkov poll_drift_i_, poll_drift_q_;  // slow part of the pick-up's envelope
  noise::BandNoise vib_;
  noise::LineBand intf_;
  double sense_sd_ = 0, input_sd_ = 0, rrw_step_ = 0, rrw_ = 0;
  noise::Oscillator poll_osc_;
  std::array<noise::Oscillator, kBurstTones> burst_osc_{};
  std::array<double, kBurstTones> burst_env_{};
  double burst_p_ = 0, burst_decay_ = 1;
};

// PeriodNoise run on a worker thread, up to `depth` blocks ahead of the reader: a ring of
// blocks (one arena, on huge pages where the kernel offers them) handed over under one mutex:
// one hand-over per block, not per sample, and a sleeping side is woken once per depth / 2
// blocks, not at every block. The worker
// only computes; it stops and is joined when the pipe is destroyed, whatever the reader was
// doing (an abort, a fault in a phase).
class NoisePipe {
 public:
  NoisePipe(PeriodNoise source, std::size_t periods_per_block, std::size_t depth);
  ~NoisePipe();
  NoisePipe(const NoisePipe&) = delete;
  NoisePipe& operator=(const NoisePipe&) = delete;

  // The oldest block not yet released; when none is drawn, waits until half the ring is.
  const NoiseBlock& front();
  // Gives the front block back to the worker.
  void pop();

 private:
  void run();

  PeriodNoise source_;
  std::unique_ptr<double[]> arena_;  // the ring's terms
  std::vector<NoiseBlock> ring_;
  // A sleeping worker is woken when at most low_ blocks are left unread, a sleeping reader when
  // ready_ are drawn: half a ring each way (a reader of a ring of one waits for its one block).
  std::size_t low_ = 0, ready_ = 1;
  std::mutex m_;  // guards the counts and flags below
  std::condition_variable worker_cv_, reader_cv_;
  uint64_t drawn_ = 0, released_ = 0;  // blocks
  bool stop_ = false, worker_waiting_ = false, reader_waiting_ = false;
  std::thread worker_;  // last: starts after everything it reads is built
};

}  // namespace rig::plant
