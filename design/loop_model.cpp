#include "design/loop_model.hpp"

#include <cmath>
#include <numbers>

#include <unsupported/Eigen/MatrixFunctions>

namespace rig::design {

LoopModel::LoopModel(const LoopParams& lp, const RegulatorParams& rp) {
  rate_ = lp.loop_rate_hz;
  const double T = 1.0 / rate_;
  // Continuous part, states (theta, omega, i), inputs (q in g, i_cmd in A):
  //   J theta'' = ml g q - c theta' - k theta - K_дм i,   i' = (i_cmd - i) / tau_coil.
  const double J = lp.inertia_kg_m2;
  Eigen::Matrix<double, 5, 5> m = Eigen::Matrix<double, 5, 5>::Zero();
  m(0, 1) = 1;
  m(1, 0) = -lp.stiffness_n_m_rad / J;
  m(1, 1) = -lp.damping_n_m_s / J;
  m(1, 2) = -lp.torquer_n_m_a / J;
  m(2, 2) = -1 / lp.coil_tau_s;
  m(1, 3) = lp.pendulosity_kg_m * lp.g_local_m_s2 / J;  // q input
  m(2, 4) = 1 / lp.coil_tau_s;                          // i_cmd input
  // Zero-order hold: exp([[A, B], [0, 0]] T) = [[Ad, Bd], [0, I]].
  const Eigen::Matrix<double, 5, 5> e = (m * T).exp();
  ad_ = e.topLeftCorner<3, 3>();
  bq_ = e.block<3, 1>(0, 3);
  bi_ = e.block<3, 1>(0, 4);

  kpick_ = lp.angle_sensor_v_rad * lp.preamp_gain;
  adc_range_ = lp.adc_range_v;
  adc_lsb_ = 2 * lp.adc_range_v / std::ldexp(1.0, lp.adc_bits);
  adc_inv_lsb_ = 1 / adc_lsb_;

  reg_ = regulator_biquad(rp, rate_);

  pwm_fs_ = lp.pwm_full_scale_a;
  inv_pwm_fs_ = 1 / pwm_fs_;
  pwm_counts_ = lp.pwm_counts;
  inv_pwm_counts_ = 1.0 / lp.pwm_counts;
  // x in g: the torquer's moment per g of input, K_дм i / (ml g).
  x_per_amp_ = lp.torquer_n_m_a / (lp.pendulosity_kg_m * lp.g_local_m_s2);
  delay_ = lp.delay_steps > 0;
}

LinearLoop LoopModel::linear() const {
  // State z = (theta, omega, i, i_cmd, w1, w2). Regulator input v = kpick theta.
  const int n = 6;
  LinearLoop l;
  l.rate_hz = rate_;
  l.A = Eigen::MatrixXd::Zero(n, n);
  l.B = Eigen::VectorXd::Zero(n);
  l.C = Eigen::RowVectorXd::Zero(n);
  // Regulator output u = w1 + b0 v as a row over z.
  Eigen::RowVectorXd u = Eigen::RowVectorXd::Zero(n);
  u(0) = reg_.b0 * kpick_;
  u(4) = 1;
  // i used by the plant in this period: i_cmd (delayed) or u (no delay).
  Eigen::RowVectorXd iu = Eigen::RowVectorXd::Zero(n);
  if (delay_) iu(3) = 1; else iu = u;
  l.A.topLeftCorner(3, 3) = ad_;
  l.A.topRows(3) += bi_ * iu;
  l.B.head(3) = bq_;
  l.A.row(3) = u;  // i_cmd' = u
  // w1' = b1 v - a1 u + w2;  w2' = b2 v - a2 u
  l.A.row(4) = -reg_.a1 * u;
  l.A(4, 0) += reg_.b1 * kpick_;
  l.A(4, 5) += 1;
  l.A.row(5) = -reg_.a2 * u;
  l.A(5, 0) += reg_.b2 * kpick_;
  l.C(2) = x_per_amp_;
  return l;
}

std::complex<double> loop_response(const LinearLoop& l, double f_hz) {
  const auto n = l.A.rows();
  const std::complex<double> z = std::polar(1.0, 2 * std::numbers::pi * f_hz / l.rate_hz);
  Eigen::MatrixXcd m = z * Eigen::MatrixXcd::Identity(n, n) - l.A.cast<std::complex<double>>();
  const Eigen::VectorXcd v = m.partialPivLu().solve(l.B.cast<std::complex<double>>());
  return (l.C.cast<std::complex<double>>() * v)(0);
}

std::vector<double> loop_step(const LinearLoop& l, std::size_t n) {
  std::vector<double> out(n);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(l.A.rows());
  for (std::size_t k = 0; k < n; ++k) {
    out[k] = l.C * z;
    z = l.A * z + l.B;
  }
  return out;
}

}  // namespace rig::design
