// The emulated quartz pendulum accelerometer: closed loop + noise + orientation,
// stepped at the loop rate and polled by sample-and-hold at the output rate.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "design/filter.hpp"
#include "design/loop_model.hpp"
#include "plant/dut/params.hpp"
#include "plant/dut/period_noise.hpp"
#include "plant/emulated/dut_source.hpp"

namespace rig::plant {

// The noise worker's hand-over: blocks of about this many loop steps (whole periods: 1024 at
// the default 10 steps a period), this many drawn ahead; sized in steps, so the ring stays
// about 14 MB whatever the loop and output rates.
inline constexpr std::size_t kNoiseBlockSteps = 10240, kNoiseBlocksAhead = 16;
inline std::size_t noise_block_periods(std::size_t steps_per_period) {
  return std::max<std::size_t>(1, kNoiseBlockSteps / std::max<std::size_t>(steps_per_period, 1));
}

class EmulatedDut final : public DutSource {
 public:
  EmulatedDut(const DutParams& p, uint64_t seed);

  double output_rate_hz() const override { return p_.loop.output_rate_hz; }
  void set_table_angle_deg(double deg) override;
  void next(float& x_g, float& y_g) override;
  void set_filter(const FilterConfig& f) override;
  FilterConfig filter() const override { return filter_cfg_; }
  bool filter_enabled() const override { return filter_cfg_.enabled; }
  double temperature_c() const override { return temp_c_; }
  std::string serial() const override { return p_.serial; }
  int loop_steps_per_output() const override { return steps_per_out_; }
  bool next_under_test(double torque_g, std::span<float> x_loop, std::span<float> y_loop) override;

  // Full-precision outputs (before the float conversion of the seam), for tests and tools.
  void next(double& x_g, double& y_g);
  // Gravity component along the sensitive axis at the current table angle (g).
  double static_input_g() const { return q_static_; }
  double time_s() const { return static_cast<double>(n_out_) / p_.loop.output_rate_hz; }
  bool saturated() const { return st_.saturated; }
  const DutParams& params() const { return p_; }
  const design::LoopModel& loop() const { return loop_; }

 private:
  // One output period: `q_test_g` (the loop test's torque as input acceleration) adds to the
  // input; the loop-rate x and y go to the taps when given.
  void period(double q_test_g, float* x_tap, float* y_tap, double& x_out, double& y_out);
  double word(double v, double& carry) const;

  DutParams p_;
  design::LoopModel loop_;
  design::LoopModel::State st_;
  int steps_per_out_;
  uint64_t n_out_ = 0;
  double q_static_ = 0;
  double angle_deg_ = std::numeric_limits<double>::quiet_NaN();
  double temp_c_ = 0;

  // The noise sources, drawn ahead on the pipe's worker thread (plant/dut/period_noise.hpp);
  // the period being stepped is period_ of the front block.
  bool has_input_ = false, has_sense_ = false;
  double sense_lsb_ = 0, sense_inv_lsb_ = 0;
  std::unique_ptr<NoisePipe> noise_;
  const NoiseBlock* block_ = nullptr;
  std::size_t period_ = 0;

  // output filter W_f(z), DF-II-T sections at the loop rate
  FilterConfig filter_cfg_;
  std::vector<design::Section> filt_;
  double carry_x_ = 0, carry_y_ = 0;
  bool tap_saturated_ = false;  // the loop saturated (ADC or PWM) during a loop-test period
};

}  // namespace rig::plant
