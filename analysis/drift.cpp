#include "analysis/drift.hpp"

#include <numbers>

namespace rig::analysis {

Drift least_squares_drift(std::span<const double> y, double rate_hz) {
  Drift d;
  d.n = y.size();
  d.tau0 = rate_hz > 0 ? 1 / rate_hz : 0;
  if (!d.ok()) return d;
  const double n = static_cast<double>(d.n), mid = (n - 1) / 2;
  CompensatedSum s;
  for (std::size_t k = 0; k < y.size(); ++k) s.add((static_cast<double>(k) - mid) * y[k]);
  d.slope = s.value() / (d.tau0 * n * (n * n - 1) / 12);
  return d;
}

Drift drift_from_phase_sums(std::uint64_t n, double p_last, double p_sum, double tau0) {
  Drift d;
  d.n = n;
  d.tau0 = tau0;
  if (!d.ok()) return d;
  const double nn = static_cast<double>(n);
  d.slope = ((nn + 1) / 2 * p_last - p_sum) / (tau0 * nn * (nn * nn - 1) / 12);
  return d;
}

std::array<double, 4> drift_variance_terms(const std::array<double, 4>& q, const Drift& d) {
  if (!d.ok()) return {};
  const double T = d.length_s();
  return {72 * q[0] * q[0] / (T * T * T * T), 12 * q[1] * q[1] / (T * T * T),
          9 * q[2] * q[2] / (std::numbers::pi * T * T), 6 * q[3] * q[3] / (5 * T)};
}

}  // namespace rig::analysis
