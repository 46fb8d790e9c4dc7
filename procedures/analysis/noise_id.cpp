#include "procedures/analysis/noise_id.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rig::analysis {

double lag1_acf(std::span<const double> x) {
  const std::size_t n = x.size();
  if (n < 2) return 0;
  double mu = 0;
  for (double v : x) mu += v;
  mu /= static_cast<double>(n);
  double a = 0, b = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) a += (x[i] - mu) * (x[i + 1] - mu);
  for (double v : x) b += (v - mu) * (v - mu);
  return b > 0 ? a / b : 0;
}

namespace {

// Residual of the least-squares line over t = 0..n-1 (closed form, centred t).
std::vector<double> detrend_linear(std::span<const double> x) {
  const double n = static_cast<double>(x.size()), tm = (n - 1) / 2;
  double mean = 0;
  for (double v : x) mean += v;
  mean /= n;
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double t = static_cast<double>(i) - tm;
    sxy += t * (x[i] - mean);
    sxx += t * t;
  }
  const double b = sxx > 0 ? sxy / sxx : 0;
  std::vector<double> r(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) r[i] = x[i] - mean - b * (static_cast<double>(i) - tm);
  return r;
}

// Residual of a least-squares polynomial of degree `deg` (t scaled to [-1, 1]).
std::vector<double> detrend(std::span<const double> x, int deg) {
  if (deg == 1) return detrend_linear(x);
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd A(n, deg + 1);
  const double half = (static_cast<double>(n) - 1) / 2;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = half > 0 ? (static_cast<double>(i) - half) / half : 0;
    double p = 1;
    for (int k = 0; k <= deg; ++k, p *= t) A(i, k) = p;
  }
  const Eigen::Map<const Eigen::VectorXd> b(x.data(), n);
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd r = b - A * c;
  return {r.data(), r.data() + n};
}

}  // namespace

NoiseId acf_noise_id(std::span<const double> series, bool phase, int dmax) {
  std::vector<double> x = detrend(series, phase ? 2 : 1);
  NoiseId id;
  for (int d = 0;; ++d) {
    const double r1 = lag1_acf(x);
    const double rho = r1 / (1 + r1);
    if (rho < 0.25 || d >= dmax) {
      const int add = phase ? 2 : 0;
      id.rho = rho;
      id.d = d;
      id.alpha_f = -2 * (rho + d) + add;
      id.alpha = static_cast<int>(-std::nearbyint(2 * rho)) - 2 * d + add;  // round half to even, as Stable32/NumPy
      id.acf = true;
      return id;
    }
    for (std::size_t i = 0; i + 1 < x.size(); ++i) x[i] = x[i + 1] - x[i];
    x.pop_back();
  }
}

double b1_theory(double n, int mu) {
  switch (mu) {
    case 2: return n * (n + 1) / 6;
    case 1: return n / 2;
    case 0: return n * std::log(n) / (2 * (n - 1) * std::log(2.0));
    case -1: return 1;
    case -2: return (n * n - 1) / (1.5 * n * (n - 1));
    default: return n * (1 - std::pow(n, mu)) / (2 * (n - 1) * (1 - std::pow(2.0, mu)));
  }
}

double rn_theory(std::size_t m, int alpha) {
  const double af = static_cast<double>(m);
  if (alpha == 2) return 1 / af;
  if (alpha == 1) {  // flicker PM with f_h = 1/(2 tau0) (IEEE 1139)
    const double pi = std::numbers::pi;
    const double avar = (1.038 + 3 * std::log(2 * pi * 0.5 * af)) / (4 * pi * pi);
    const double mvar = 3 * std::log(256.0 / 27.0) / (8 * pi * pi);
    return mvar / avar;
  }
  return 1;
}

NoiseId b1_rn_noise_id(double b1, double n, double rn, std::size_t m) {
  // Candidates mu = 2 (alpha -3) .. -2 (alpha 2/1); boundaries at the geometric means of neighbours.
  NoiseId id;
  id.acf = false;
  int mu = -2;
  for (int cand = 2; cand > -2; --cand) {
    const double hi = b1_theory(n, cand), lo = b1_theory(n, cand - 1);
    if (b1 > std::sqrt(hi * lo)) {
      mu = cand;
      break;
    }
  }
  // mu -> alpha: 2 -> -3, 1 -> -2, 0 -> -1, -1 -> 0, -2 -> PM (R(n) decides).
  if (mu > -2) {
    id.alpha = -mu - 1;
  } else if (rn >= 0) {
    id.alpha = rn > std::sqrt(rn_theory(m, 2) * rn_theory(m, 1)) ? 1 : 2;
  } else {
    id.alpha = 1;
  }
  id.alpha_f = id.alpha;
  return id;
}

}  // namespace rig::analysis
