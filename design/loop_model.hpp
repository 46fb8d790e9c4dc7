// The DUT's closed loop (docs/method.md Fig. 3): pendulum W_m(s) with pendulosity ml,
// angle sensor K_ду, preamplifier K_пу, ADC, digital regulator W_рег(z), PWM K_шим,
// torquer K_дм. The continuous part (pendulum + torquer coil) is discretised
// exactly for the zero-order-held PWM current by the matrix exponential.
// The design-time model of the loop: the emulated DUT (plant/dut) steps it with its noise,
// and the closed-loop figures (design/loop_figures.hpp) come from its linear form.
#pragma once
#include <algorithm>
#include <complex>
#include <vector>

#include <Eigen/Dense>

#include "design/filter.hpp"
#include "design/loop_params.hpp"
#include "design/quantise.hpp"

namespace rig::design {

// The closed loop as one linear discrete system at the loop rate (quantisers and
// saturation left out): z' = A z + B q, x = C z. Input q and output x in g.
struct LinearLoop {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C;
  double rate_hz = 10000;
};

class LoopModel {
 public:
  struct State {
    Eigen::Vector3d s = Eigen::Vector3d::Zero();  // pendulum angle (rad), rate (rad/s), coil current (A)
    double i_cmd = 0;                             // PWM current applied in this period (A)
    double w1 = 0, w2 = 0;                        // regulator (DF-II-T biquad) state
    bool saturated = false;                       // this period: pick-off ADC clipped or PWM duty clipped
  };

  LoopModel(const LoopParams& lp, const RegulatorParams& rp);

  // One loop period. `q_g`: input acceleration along the sensitive axis (g), held
  // over the period; `pickoff_v`: noise at the ADC input (V). Returns x (g): the
  // coil current at the start of the period, scaled by the nominal scale factor.
  [[gnu::always_inline]] double step(State& st, double q_g, double pickoff_v = 0) const {
    const double th = st.s(0), om = st.s(1), cur = st.s(2);
    const double x = x_per_amp_ * cur;
    // ADC of the pick-off voltage (mid-tread, clipped to its range). A clipped pick-off leaves
    // the loop as nonlinear as a clipped duty (a strong step then slews instead of settling), so
    // both count as saturated: the loop test's figures are not read from such a step.
    double v = kpick_ * th + pickoff_v;
    const bool clipped = v > adc_range_ || v < -adc_range_;
    v = std::clamp(v, -adc_range_, adc_range_);
    v = adc_lsb_ * round_half_even(v * adc_inv_lsb_);
    // W_рег(z): one DF-II-T biquad.
    const double u = df2t_step(reg_, st.w1, st.w2, v);
    // PWM: duty clipped to +-1 and quantised to the timer's counts.
    double duty = u * inv_pwm_fs_;
    st.saturated = clipped || duty > 1 || duty < -1;
    duty = std::clamp(duty, -1.0, 1.0);
    const double i_new = pwm_fs_ * round_half_even(duty * pwm_counts_) * inv_pwm_counts_;
    const double i_used = delay_ ? st.i_cmd : i_new;
    st.i_cmd = i_new;
    // ZOH-exact update of the continuous part (written out: 3x3, hot path).
    st.s(0) = ad_(0, 0) * th + ad_(0, 1) * om + ad_(0, 2) * cur + bq_(0) * q_g + bi_(0) * i_used;
    st.s(1) = ad_(1, 0) * th + ad_(1, 1) * om + ad_(1, 2) * cur + bq_(1) * q_g + bi_(1) * i_used;
    st.s(2) = ad_(2, 0) * th + ad_(2, 1) * om + ad_(2, 2) * cur + bq_(2) * q_g + bi_(2) * i_used;
    return x;
  }

  LinearLoop linear() const;
  double x_per_amp() const { return x_per_amp_; }
  double rate_hz() const { return rate_; }
  // The regulator's coefficients (b0, b1, b2, a1, a2), for the docs and tests.
  Biquad regulator() const { return reg_; }

 private:
  Eigen::Matrix3d ad_;
  Eigen::Vector3d bq_, bi_;
  double rate_, kpick_, adc_range_, adc_lsb_, adc_inv_lsb_;
  Biquad reg_;
  double pwm_fs_, inv_pwm_fs_, pwm_counts_, inv_pwm_counts_;
  double x_per_amp_;
  bool delay_;
};

// Frequency response of the linear closed loop (q -> x) at f_hz.
std::complex<double> loop_response(const LinearLoop& l, double f_hz);
// Step response of the linear loop to a unit step in q: x at each loop period.
std::vector<double> loop_step(const LinearLoop& l, std::size_t n);

}  // namespace rig::design
